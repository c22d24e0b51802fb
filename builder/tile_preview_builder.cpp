#include "builder/tile_preview_builder.hpp"

#include "codec/decoded_tile.hpp"

namespace shadowtiles {

Result<store::TilePreview> make_tile_preview(const TileIntervals& intervals, store::Method method,
                                             std::span<const uint8_t> payload) {
  auto decoded = decode_tile(method, payload);
  if (!decoded) return decoded.error();
  if ((*decoded)->size() != intervals.size)
    return make_error(ErrorCode::corrupt_data, "decoded tile side differs from the rendered tile's");
  store::TilePreview preview;
  preview.size = store::preview_size_for(intervals.size);
  preview.step = intervals.size / preview.size;
  const size_t count = size_t(preview.size) * preview.size;
  preview.lower.resize(count);
  preview.value.resize(count);
  preview.width.resize(count);
  for (uint32_t j = 0; j < preview.size; ++j) {
    for (uint32_t i = 0; i < preview.size; ++i) {
      const uint32_t u = i * preview.step + preview.step / 2, v = j * preview.step + preview.step / 2;
      const DepthInterval& texel = intervals.at(u, v);
      const size_t k = preview.index(i, j);
      preview.lower[k] = texel.lower;
      preview.value[k] = (*decoded)->value(u, v);
      preview.width[k] = texel.upper - texel.lower;
    }
  }
  return preview;
}

}  // namespace shadowtiles
