#include "store/tile_preview.hpp"

#include <cassert>
#include <cstring>
#include <string>

#include "store/blob.hpp"

namespace shadowtiles::store {
namespace {

void put_u16(uint8_t* out, uint16_t v) {
  out[0] = uint8_t(v);
  out[1] = uint8_t(v >> 8);
}
void put_u32(uint8_t* out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out[i] = uint8_t(v >> (8 * i));
}
uint16_t get_u16(const uint8_t* in) { return uint16_t(in[0] | (in[1] << 8)); }
uint32_t get_u32(const uint8_t* in) {
  uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= uint32_t(in[i]) << (8 * i);
  return v;
}

void put_plane(uint8_t* out, const std::vector<float>& plane) {
  for (size_t k = 0; k < plane.size(); ++k) {
    uint32_t bits;
    std::memcpy(&bits, &plane[k], 4);
    put_u32(out + 4 * k, bits);
  }
}
std::vector<float> get_plane(const uint8_t* in, size_t count) {
  std::vector<float> plane(count);
  for (size_t k = 0; k < count; ++k) {
    uint32_t bits = get_u32(in + 4 * k);
    std::memcpy(&plane[k], &bits, 4);
  }
  return plane;
}

}  // namespace

std::vector<uint8_t> encode_preview(Method method, const TilePreview& preview, int zstd_level) {
  const size_t count = size_t(preview.size) * preview.size;
  assert(preview.size >= 1 && preview.lower.size() == count && preview.value.size() == count &&
         preview.width.size() == count);
  std::vector<uint8_t> payload(kPreviewHeaderSize + 3 * 4 * count);
  std::memcpy(payload.data(), kPreviewMagic, 4);
  put_u16(payload.data() + 4, kPreviewFormatVersion);
  put_u16(payload.data() + 6, 3);
  put_u32(payload.data() + 8, preview.size);
  put_u32(payload.data() + 12, preview.step);
  uint8_t* planes = payload.data() + kPreviewHeaderSize;
  put_plane(planes, preview.lower);
  put_plane(planes + 4 * count, preview.value);
  put_plane(planes + 8 * count, preview.width);
  return encode_blob(method, payload, 0, zstd_level);
}

Result<TilePreview> decode_preview(std::span<const uint8_t> blob, Method expected) {
  BlobHeader header{};
  auto payload = decode_blob(blob, &header);
  if (!payload) return payload.error();
  if (header.method != expected)
    return make_error(ErrorCode::corrupt_data, "preview record holds another method than its key");
  const std::vector<uint8_t>& p = *payload;
  if (p.size() < kPreviewHeaderSize || std::memcmp(p.data(), kPreviewMagic, 4) != 0)
    return make_error(ErrorCode::corrupt_data, "preview record: bad magic or truncated header");
  uint16_t version = get_u16(p.data() + 4);
  if (version > kPreviewFormatVersion)
    return make_error(ErrorCode::unsupported, "preview record version " + std::to_string(version) +
                                                  " is newer than this build reads");
  if (version == 0 || get_u16(p.data() + 6) != 3)
    return make_error(ErrorCode::corrupt_data, "preview record: bad version or plane count");
  TilePreview preview;
  preview.size = get_u32(p.data() + 8);
  preview.step = get_u32(p.data() + 12);
  // Sides are powers of two up to 2^20 texels per tile; anything else is damage.
  if (preview.size == 0 || preview.size > 4096 || (preview.size & (preview.size - 1)) || preview.step == 0 ||
      preview.step > (1u << 20) || (preview.step & (preview.step - 1)))
    return make_error(ErrorCode::corrupt_data, "preview record: bad size or step");
  const size_t count = size_t(preview.size) * preview.size;
  if (p.size() != kPreviewHeaderSize + 12 * count)
    return make_error(ErrorCode::corrupt_data, "preview record: payload size does not match its side");
  const uint8_t* planes = p.data() + kPreviewHeaderSize;
  preview.lower = get_plane(planes, count);
  preview.value = get_plane(planes + 4 * count, count);
  preview.width = get_plane(planes + 8 * count, count);
  return preview;
}

}  // namespace shadowtiles::store
