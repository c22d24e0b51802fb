#include "store/tile_key.hpp"

#include <string>

#include "common/byte_order.hpp"

namespace shadowtiles::store {

std::array<uint8_t, kTileKeySize> encode_tile_key(const TileKey& key) {
  std::array<uint8_t, kTileKeySize> bytes{};
  bytes[0] = static_cast<uint8_t>(key.method);
  bytes[1] = key.level;
  bytes::store_be<uint32_t>(bytes.data() + 2, key.x);
  bytes::store_be<uint32_t>(bytes.data() + 6, key.y);
  return bytes;
}

Result<TileKey> decode_tile_key(std::span<const uint8_t> bytes) {
  if (bytes.size() != kTileKeySize) {
    return make_error(ErrorCode::invalid_input, "tile key has " + std::to_string(bytes.size()) +
                                                    " bytes, expected " +
                                                    std::to_string(kTileKeySize));
  }
  Result<Method> method = method_from_byte(bytes[0]);
  if (!method) return make_error(ErrorCode::invalid_input, "tile key: " + method.error().message);
  return TileKey{*method, bytes[1], bytes::load_be<uint32_t>(bytes.data() + 2),
                 bytes::load_be<uint32_t>(bytes.data() + 6)};
}

std::array<uint8_t, kTileKeyPrefixSize> tile_key_prefix(Method method, uint8_t level) {
  return {static_cast<uint8_t>(method), level};
}

}  // namespace shadowtiles::store
