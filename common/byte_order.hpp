// The one byte-loading header: fixed-width loads and stores of the project's on-disk formats.
// - store_le/load_le, store_be/load_be: explicit byte order, any host (tile keys are big-endian so
//   memcmp order is numeric; blob headers and payload fields are little-endian).
// - load_unaligned/load_f32/load_u16/load_u32/load_u64: native little-endian loads at any byte offset
//   through memcpy (no alignment or aliasing assumptions; one move each), for the decoders' hot paths.
// - load_le_width: an unsigned field of 1..8 bytes (variable-width references).
// Preconditions: the pointer addresses at least as many bytes as the field. Thread safety: pure.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>

namespace shadowtiles::bytes {

static_assert(std::endian::native == std::endian::little,
              "decoders read payload fields with memcpy: little-endian hosts only");

template <class T>
inline void store_le(uint8_t* out, T value) {
  for (size_t i = 0; i < sizeof(T); ++i) out[i] = static_cast<uint8_t>(value >> (8 * i));
}

template <class T>
inline T load_le(const uint8_t* in) {
  T value = 0;
  for (size_t i = 0; i < sizeof(T); ++i) value |= static_cast<T>(static_cast<T>(in[i]) << (8 * i));
  return value;
}

template <class T>
inline void store_be(uint8_t* out, T value) {
  for (size_t i = 0; i < sizeof(T); ++i) out[i] = static_cast<uint8_t>(value >> (8 * (sizeof(T) - 1 - i)));
}

template <class T>
inline T load_be(const uint8_t* in) {
  T value = 0;
  for (size_t i = 0; i < sizeof(T); ++i) value = static_cast<T>((value << 8) | in[i]);
  return value;
}

template <typename T>
inline T load_unaligned(const uint8_t* p) {
  T value;
  std::memcpy(&value, p, sizeof(T));
  return value;
}
inline float load_f32(const uint8_t* p) { return load_unaligned<float>(p); }
inline uint16_t load_u16(const uint8_t* p) { return load_unaligned<uint16_t>(p); }
inline uint32_t load_u32(const uint8_t* p) { return load_unaligned<uint32_t>(p); }
inline uint64_t load_u64(const uint8_t* p) { return load_unaligned<uint64_t>(p); }

// An unsigned little-endian field of `width` bytes (1..8).
inline uint64_t load_le_width(const uint8_t* in, unsigned width) {
  uint64_t v = 0;
  for (unsigned i = 0; i < width; ++i) v |= uint64_t(in[i]) << (8 * i);
  return v;
}

}  // namespace shadowtiles::bytes
