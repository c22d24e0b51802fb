#include "store/tile_info.hpp"

#include <bit>
#include <cmath>
#include <string>

#include "common/byte_order.hpp"

namespace shadowtiles::store {

std::array<uint8_t, kTileInfoSize> encode_tile_info(const TileInfo& info) {
  std::array<uint8_t, kTileInfoSize> out{};
  out[0] = kTileInfoFormatVersion;
  out[1] = info.has_root ? 1 : 0;
  bytes::store_le<uint32_t>(out.data() + 4, std::bit_cast<uint32_t>(info.root_lower));
  bytes::store_le<uint32_t>(out.data() + 8, std::bit_cast<uint32_t>(info.root_upper));
  bytes::store_le<uint64_t>(out.data() + 12, info.blob_bytes);
  bytes::store_le<uint64_t>(out.data() + 20, info.payload_bytes);
  return out;
}

Result<TileInfo> decode_tile_info(std::span<const uint8_t> in) {
  if (in.size() != kTileInfoSize)
    return make_error(ErrorCode::corrupt_data,
                      "tile info: " + std::to_string(in.size()) + " bytes, expected " + std::to_string(kTileInfoSize));
  if (in[0] > kTileInfoFormatVersion)
    return make_error(ErrorCode::unsupported, "tile info: format version " + std::to_string(in[0]) +
                                                  " is newer than this build reads (" +
                                                  std::to_string(kTileInfoFormatVersion) + ")");
  if (in[0] == 0) return make_error(ErrorCode::corrupt_data, "tile info: format version 0");
  if ((in[1] & ~1u) != 0 || bytes::load_le<uint16_t>(in.data() + 2) != 0)
    return make_error(ErrorCode::corrupt_data, "tile info: unknown flag or reserved bits set");
  TileInfo info;
  info.has_root = in[1] & 1;
  info.root_lower = std::bit_cast<float>(bytes::load_le<uint32_t>(in.data() + 4));
  info.root_upper = std::bit_cast<float>(bytes::load_le<uint32_t>(in.data() + 8));
  info.blob_bytes = bytes::load_le<uint64_t>(in.data() + 12);
  info.payload_bytes = bytes::load_le<uint64_t>(in.data() + 20);
  if (std::isnan(info.root_lower) || std::isnan(info.root_upper) || !(info.root_lower <= info.root_upper))
    return make_error(ErrorCode::corrupt_data, "tile info: root interval is NaN or inverted");
  return info;
}

}  // namespace shadowtiles::store
