#include "codec/raw_tile.hpp"

#include <bit>
#include <cstring>
#include <string>

namespace shadowtiles {

std::vector<uint8_t> encode_raw_tile(uint32_t size, std::span<const float> lower) {
  static_assert(std::endian::native == std::endian::little, "payload formats are little-endian");
  std::vector<uint8_t> out(4 + lower.size_bytes());
  std::memcpy(out.data(), &size, 4);
  std::memcpy(out.data() + 4, lower.data(), lower.size_bytes());
  return out;
}

Result<RawTileView> RawTileView::parse(std::span<const uint8_t> payload) {
  if (payload.size() < 4) return make_error(ErrorCode::corrupt_data, "raw tile: payload shorter than its header");
  uint32_t size;
  std::memcpy(&size, payload.data(), 4);
  if (!std::has_single_bit(size) || size > (1u << 14))
    return make_error(ErrorCode::corrupt_data, "raw tile: bad tile size " + std::to_string(size));
  uint64_t expected = 4 + uint64_t(size) * size * sizeof(float);
  if (payload.size() != expected)
    return make_error(ErrorCode::corrupt_data, "raw tile: payload is " + std::to_string(payload.size()) +
                                                   " bytes, expected " + std::to_string(expected));
  RawTileView view;
  view.size_ = size;
  view.values_.resize(size_t(size) * size);
  std::memcpy(view.values_.data(), payload.data() + 4, view.values_.size() * sizeof(float));
  return view;
}

}  // namespace shadowtiles
