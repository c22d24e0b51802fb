// Directed rounding of a double to a float: the nearest float on the safe side of an exact bound
// (builds store floats; a bound rounded the wrong way by half a step would break a proof).
// Thread safety: pure functions.
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

namespace shadowtiles {

// The next float above a finite `f` (std::nextafter without the library call: builds take it per texel).
inline float next_float_up(float f) {
  if (f == 0.0f) return std::numeric_limits<float>::denorm_min();
  const uint32_t bits = std::bit_cast<uint32_t>(f);
  return std::bit_cast<float>(f > 0.0f ? bits + 1 : bits - 1);
}

// The smallest float not below `x`.
inline float float_at_least(double x) {
  const float f = float(x);
  return double(f) < x ? next_float_up(f) : f;
}

// The largest float not above `x`.
inline float float_at_most(double x) {
  float f = float(x);
  if (double(f) > x) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}

}  // namespace shadowtiles
