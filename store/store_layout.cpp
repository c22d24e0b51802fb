#include "store/store_layout.hpp"

#include <bit>
#include <cmath>

#include "common/byte_order.hpp"

namespace shadowtiles::store {

std::array<uint8_t, kProgressKeySize> progress_key(uint32_t tile_x, uint32_t tile_y) {
  std::array<uint8_t, kProgressKeySize> key{};
  bytes::store_be<uint32_t>(key.data(), tile_x);
  bytes::store_be<uint32_t>(key.data() + 4, tile_y);
  return key;
}

Result<ProgressTile> decode_progress_key(std::span<const uint8_t> key) {
  if (key.size() != kProgressKeySize)
    return make_error(ErrorCode::corrupt_data, "progress key of " + std::to_string(key.size()) + " bytes, not 8");
  return ProgressTile{bytes::load_be<uint32_t>(key.data()), bytes::load_be<uint32_t>(key.data() + 4)};
}

std::array<uint8_t, kProgressRecordSize> encode_progress(const ProgressRecord& record) {
  std::array<uint8_t, kProgressRecordSize> value{};
  value[0] = record.stored ? 1 : 0;
  bytes::store_le<uint32_t>(value.data() + 1, std::bit_cast<uint32_t>(record.root_lower));
  bytes::store_le<uint32_t>(value.data() + 5, std::bit_cast<uint32_t>(record.root_upper));
  return value;
}

Result<ProgressRecord> decode_progress(std::span<const uint8_t> value) {
  if (value.size() != kProgressRecordSize)
    return make_error(ErrorCode::corrupt_data, "progress record of " + std::to_string(value.size()) + " bytes, not 9");
  if (value[0] > 1) return make_error(ErrorCode::corrupt_data, "progress record: stored flag not 0 or 1");
  ProgressRecord record;
  record.stored = value[0] == 1;
  record.root_lower = std::bit_cast<float>(bytes::load_le<uint32_t>(value.data() + 1));
  record.root_upper = std::bit_cast<float>(bytes::load_le<uint32_t>(value.data() + 5));
  if (std::isnan(record.root_lower) || std::isnan(record.root_upper) || record.root_lower > record.root_upper)
    return make_error(ErrorCode::corrupt_data, "progress record: root interval NaN or inverted");
  return record;
}

}  // namespace shadowtiles::store
