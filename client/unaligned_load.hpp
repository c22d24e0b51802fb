// Loads of little-endian fields at any byte offset of a payload (memcpy: no alignment or aliasing
// assumptions; compiles to one move). Shared by the MH, DAG-MH and SST readers.
#pragma once

#include <bit>
#include <cstdint>
#include <cstring>

namespace shadowtiles {

static_assert(std::endian::native == std::endian::little, "payloads are read with memcpy: little-endian only");

template <typename T>
inline T load_unaligned(const uint8_t* p) {
  T value;
  std::memcpy(&value, p, sizeof(T));
  return value;
}
inline float load_f32(const uint8_t* p) { return load_unaligned<float>(p); }
inline uint16_t load_u16(const uint8_t* p) { return load_unaligned<uint16_t>(p); }
inline uint32_t load_u32(const uint8_t* p) { return load_unaligned<uint32_t>(p); }

}  // namespace shadowtiles
