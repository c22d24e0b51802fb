// Fixed-width integer load/store in explicit byte order, for the store's on-disk formats (tile keys
// are big-endian so memcmp order is numeric; blob headers are little-endian). Internal to store/.
// Preconditions: the pointer addresses at least sizeof(T) bytes. Thread safety: pure functions.
#pragma once

#include <cstddef>
#include <cstdint>

namespace shadowtiles::store::detail {

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
  for (size_t i = 0; i < sizeof(T); ++i) {
    out[i] = static_cast<uint8_t>(value >> (8 * (sizeof(T) - 1 - i)));
  }
}

template <class T>
inline T load_be(const uint8_t* in) {
  T value = 0;
  for (size_t i = 0; i < sizeof(T); ++i) value = static_cast<T>((value << 8) | in[i]);
  return value;
}

}  // namespace shadowtiles::store::detail
