// Directed rounding of a double to a float: the nearest float on the safe side of an exact bound
// (builds store floats; a bound rounded the wrong way by half a step would break a proof).
// Thread safety: pure functions.
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

namespace shadowtiles {

// The next float above a finite `f` (std::nextafter without the library call: builds take it per
// texel), written with selects so that it compiles without branches.
inline float next_float_up(float f) {
  const uint32_t bits = std::bit_cast<uint32_t>(f);
  const float stepped = std::bit_cast<float>(f > 0.0f ? bits + 1 : bits - 1);
  return f == 0.0f ? std::numeric_limits<float>::denorm_min() : stepped;
}

// The smallest float not below `x` (both steps computed, then one picked: no branch).
inline float float_at_least(double x) {
  const float f = float(x);
  const float up = next_float_up(f);
  return double(f) < x ? up : f;
}

// The largest float not above `x`.
inline float float_at_most(double x) {
  float f = float(x);
  if (double(f) > x) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}

}  // namespace shadowtiles
