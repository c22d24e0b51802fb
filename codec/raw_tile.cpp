#include "codec/raw_tile.hpp"

#include <bit>
#include <cassert>
#include <cmath>
#include <cstring>
#include <string>

namespace shadowtiles {
namespace {

Error corrupt(const std::string& what) { return make_error(ErrorCode::corrupt_data, "raw tile: " + what); }

}  // namespace

std::vector<uint8_t> encode_raw_tile(uint32_t size, std::span<const float> lower) {
  static_assert(std::endian::native == std::endian::little, "payload formats are little-endian");
  assert(std::has_single_bit(size) && size <= kRawTileMaxSize && lower.size() == size_t(size) * size);
  std::vector<uint8_t> out(kRawTileHeaderSize + lower.size_bytes());
  std::memcpy(out.data(), kRawTileMagic, 4);
  const uint16_t version = kRawTileFormatVersion, reserved = 0;
  std::memcpy(out.data() + 4, &version, 2);
  std::memcpy(out.data() + 6, &reserved, 2);
  std::memcpy(out.data() + 8, &size, 4);
  std::memcpy(out.data() + kRawTileHeaderSize, lower.data(), lower.size_bytes());
  return out;
}

Result<RawTileView> RawTileView::parse(std::span<const uint8_t> payload) {
  if (payload.size() < 4) return corrupt("payload shorter than its header");
  size_t header = 4;  // version 0: the size word only
  uint32_t size;
  if (std::memcmp(payload.data(), kRawTileMagic, 4) == 0) {
    if (payload.size() < kRawTileHeaderSize) return corrupt("payload shorter than its header");
    uint16_t version, reserved;
    std::memcpy(&version, payload.data() + 4, 2);
    std::memcpy(&reserved, payload.data() + 6, 2);
    if (version == 0) return corrupt("format version 0 with a header");
    if (version > kRawTileFormatVersion)
      return make_error(ErrorCode::unsupported, "raw tile: format version " + std::to_string(version) +
                                                    " is newer than this build reads (" +
                                                    std::to_string(kRawTileFormatVersion) + ")");
    if (reserved != 0) return corrupt("reserved header bits set");
    std::memcpy(&size, payload.data() + 8, 4);
    header = kRawTileHeaderSize;
  } else {
    std::memcpy(&size, payload.data(), 4);
    if (!std::has_single_bit(size)) return corrupt("bad magic (neither 'STRW' nor a version-0 tile size)");
  }
  if (!std::has_single_bit(size) || size > kRawTileMaxSize) return corrupt("bad tile size " + std::to_string(size));
  const uint64_t expected = header + uint64_t(size) * size * sizeof(float);
  if (payload.size() != expected)
    return corrupt("payload is " + std::to_string(payload.size()) + " bytes, expected " + std::to_string(expected));
  RawTileView view;
  view.size_ = size;
  view.values_.resize_for_overwrite(size_t(size) * size);
  std::memcpy(view.values_.data(), payload.data() + header, view.values_.size() * sizeof(float));
  for (size_t i = 0; i < view.values_.size(); ++i)
    if (!std::isfinite(view.values_[i]))
      return corrupt("non-finite value at texel (" + std::to_string(i % size) + ", " + std::to_string(i / size) + ")");
  return view;
}

}  // namespace shadowtiles
