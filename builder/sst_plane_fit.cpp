#include "builder/sst_plane_fit.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

namespace shadowtiles {
namespace {

namespace F = sst_format;

constexpr unsigned kReweightRounds = 4;
// Half-widths below this count as this: keeps 1/width^2 finite for zero-width (open) intervals.
constexpr double kHalfWidthFloor = 1e-7;
constexpr double kReweightFactor = 8.0;

struct Slopes {
  double b = 0, c = 0;  // per texel along x (u) and y (v)
};

// Solves the 3x3 system m * s = r by Gaussian elimination with partial pivoting; false when singular.
bool solve3(std::array<std::array<double, 4>, 3> m, std::array<double, 3>& s) {
  for (int col = 0; col < 3; ++col) {
    int pivot = col;
    for (int row = col + 1; row < 3; ++row)
      if (std::fabs(m[row][col]) > std::fabs(m[pivot][col])) pivot = row;
    if (!(std::fabs(m[pivot][col]) > 1e-12 * std::fabs(m[0][0]))) return false;
    std::swap(m[col], m[pivot]);
    for (int row = col + 1; row < 3; ++row) {
      const double f = m[row][col] / m[col][col];
      for (int k = col; k < 4; ++k) m[row][k] -= f * m[col][k];
    }
  }
  for (int row = 2; row >= 0; --row) {
    double acc = m[row][3];
    for (int k = row + 1; k < 3; ++k) acc -= m[row][k] * s[k];
    s[row] = acc / m[row][row];
  }
  return true;
}

class RegionFitter {
 public:
  RegionFitter(const TileIntervals& t, uint32_t x0, uint32_t y0, uint32_t side)
      : t_(t), x0_(x0), y0_(y0), side_(side) {}

  std::optional<F::PlaneBits> fit() {
    auto& weights = scratch_weights();
    weights.assign(size_t(side_) * side_, 0.0);
    bool any = false;
    for_each([&](uint32_t i, uint32_t j, const DepthInterval& d) {
      if (!std::isfinite(d.upper)) return;  // misses only bound from below: checked, not fitted
      const double half = std::max(0.5 * (double(d.upper) - double(d.lower)), kHalfWidthFloor);
      weights[size_t(j) * side_ + i] = 1.0 / (half * half);
      any = true;
    });
    if (!any) return std::nullopt;  // all unbounded: a constant serves, the caller tries it first
    for (unsigned round = 0; round < kReweightRounds; ++round) {
      Slopes s = least_squares(weights);
      if (auto plane = quantise(s)) return plane;
      if (!reweight(s, weights)) break;
    }
    return std::nullopt;
  }

 private:
  static std::vector<double>& scratch_weights() {
    thread_local std::vector<double> weights;
    return weights;
  }

  template <class Fn>
  void for_each(Fn&& fn) const {
    for (uint32_t j = 0; j < side_; ++j)
      for (uint32_t i = 0; i < side_; ++i) fn(i, j, t_.at(x0_ + i, y0_ + j));
  }

  // Weighted least squares of the interval midpoints, in coordinates centred on the region (well
  // conditioned); falls back to zero slopes when the weighted texels are collinear.
  Slopes least_squares(const std::vector<double>& weights) const {
    const double centre = 0.5 * double(side_ - 1);
    double sw = 0, sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0, sm = 0, sxm = 0, sym = 0;
    for_each([&](uint32_t i, uint32_t j, const DepthInterval& d) {
      const double w = weights[size_t(j) * side_ + i];
      if (w == 0) return;
      const double x = double(i) - centre, y = double(j) - centre;
      const double m = std::isfinite(d.upper) ? 0.5 * (double(d.lower) + double(d.upper)) : double(d.lower);
      sw += w, sx += w * x, sy += w * y, sxx += w * x * x, sxy += w * x * y, syy += w * y * y;
      sm += w * m, sxm += w * x * m, sym += w * y * m;
    });
    std::array<double, 3> s{};
    if (!solve3({{{sw, sx, sy, sm}, {sx, sxx, sxy, sxm}, {sy, sxy, syy, sym}}}, s)) return {};
    return {s[1], s[2]};
  }

  // Tightest offset bounds for slopes (b, c) with the origin at the region's corner texel:
  // lo = max(lower - b x - c y), hi = min(upper - b x - c y).
  std::pair<double, double> offset_bounds(double b, double c) const {
    double lo = -std::numeric_limits<double>::infinity(), hi = std::numeric_limits<double>::infinity();
    for_each([&](uint32_t i, uint32_t j, const DepthInterval& d) {
      const double p = b * double(i) + c * double(j);
      lo = std::max(lo, double(d.lower) - p);
      hi = std::min(hi, double(d.upper) - p);
    });
    return {lo, hi};
  }

  // Slopes -> exponent and 16-bit slopes, offset centred in its bounds -> 24 bits, then every texel
  // checked with the decoder's expression (neighbouring offsets tried: float rounding is uneven).
  std::optional<F::PlaneBits> quantise(const Slopes& s) const {
    const double largest = std::max(std::fabs(s.b), std::fabs(s.c));
    int exponent = int(F::kMaxExponent);
    while (exponent >= 0 && std::llround(std::ldexp(largest, F::kSlopeShiftBase + exponent)) > F::kMaxSlope)
      --exponent;
    if (exponent < 0) return std::nullopt;
    F::PlaneBits plane;
    plane.E = uint8_t(exponent);
    plane.B = int16_t(std::llround(std::ldexp(s.b, F::kSlopeShiftBase + exponent)));
    plane.C = int16_t(std::llround(std::ldexp(s.c, F::kSlopeShiftBase + exponent)));
    const double step = std::ldexp(1.0, -(F::kSlopeShiftBase + exponent));
    auto [lo, hi] = offset_bounds(plane.B * step, plane.C * step);
    if (!(lo <= hi) || !std::isfinite(lo)) return std::nullopt;
    const double target = std::isfinite(hi) ? 0.5 * (lo + hi) : lo;
    const long long centre = std::llround(std::ldexp(target, F::kOffsetShift));
    for (long long candidate : {centre, centre + 1, centre - 1}) {
      if (candidate < 0 || candidate > static_cast<long long>(F::kMaxOffset)) continue;
      plane.A = uint32_t(candidate);
      if (sst_plane_fits(t_, x0_, y0_, side_, plane)) return plane;
    }
    return std::nullopt;
  }

  // Up-weights (or brings in) the texels the real-valued plane with centred offset misses; false
  // when it misses none (then only quantisation failed and reweighting cannot help).
  bool reweight(const Slopes& s, std::vector<double>& weights) const {
    auto [lo, hi] = offset_bounds(s.b, s.c);
    const double a = std::isfinite(hi) ? 0.5 * (lo + hi) : lo;
    double floor_weight = 0;
    for (double w : weights) floor_weight = std::max(floor_weight, w);
    bool changed = false;
    for_each([&](uint32_t i, uint32_t j, const DepthInterval& d) {
      const double p = a + s.b * double(i) + s.c * double(j);
      if (p >= double(d.lower) && p <= double(d.upper)) return;
      double& w = weights[size_t(j) * side_ + i];
      w = w == 0 ? floor_weight : w * kReweightFactor;
      changed = true;
    });
    return changed;
  }

  const TileIntervals& t_;
  uint32_t x0_, y0_, side_;
};

}  // namespace

bool sst_plane_fits(const TileIntervals& intervals, uint32_t x0, uint32_t y0, uint32_t side,
                    const F::PlaneBits& plane) {
  for (uint32_t j = 0; j < side; ++j)
    for (uint32_t i = 0; i < side; ++i) {
      const float value = plane.value(i, j);
      if (!intervals.at(x0 + i, y0 + j).contains(value)) return false;
    }
  return true;
}

std::optional<F::PlaneBits> fit_sst_plane(const TileIntervals& intervals, uint32_t x0, uint32_t y0, uint32_t side) {
  return RegionFitter(intervals, x0, y0, side).fit();
}

}  // namespace shadowtiles
