#include "builder/tile_preview_builder.hpp"

#include <functional>

#include "codec/dagmh_decoder.hpp"
#include "codec/decoded_tile.hpp"
#include "codec/mh_decoder.hpp"

namespace shadowtiles {
namespace {

Result<store::TilePreview> sample_preview(const TileIntervals& intervals, uint32_t decoded_size,
                                          const std::function<float(uint32_t, uint32_t)>& value) {
  if (decoded_size != intervals.size)
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
      preview.value[k] = value(u, v);
      preview.width[k] = texel.upper - texel.lower;
    }
  }
  return preview;
}

// MH, MMH and DAG-MH are read through a view over the payload, parsed (every check the client
// makes) but without the skip list a client derives: 4,096 samples do not need it, and on a
// full-depth 2048^2 tile its 65,536-262,144 walks, and copying the payload into a decoded tile,
// cost more than the samples (fzk_haus 16384^2 `anywhere`: previews were 9% of the build's CPU).
template <class View, class ParseOptions>
Result<store::TilePreview> sample_view_preview(const TileIntervals& intervals, std::span<const uint8_t> payload) {
  ParseOptions options;
  options.skip_level = 0;
  auto view = View::parse(payload, options);
  if (!view) return view.error();
  return sample_preview(intervals, view->size(), [&](uint32_t u, uint32_t v) { return view->lookup(u, v); });
}

bool mh_family(store::Method method) { return method == store::Method::mh || method == store::Method::mmh; }

}  // namespace

bool previews_decode_alike(store::Method a, store::Method b) { return a == b || (mh_family(a) && mh_family(b)); }

Result<store::TilePreview> make_tile_preview(const TileIntervals& intervals, store::Method method,
                                             std::span<const uint8_t> payload) {
  if (mh_family(method))
    return sample_view_preview<MhTileView, MhParseOptions>(intervals, payload);
  if (method == store::Method::dagmh) return sample_view_preview<DagMhTileView, DagMhParseOptions>(intervals, payload);
  auto decoded = decode_tile(method, payload);
  if (!decoded) return decoded.error();
  return sample_preview(intervals, (*decoded)->size(),
                        [&](uint32_t u, uint32_t v) { return (*decoded)->value(u, v); });
}

}  // namespace shadowtiles
