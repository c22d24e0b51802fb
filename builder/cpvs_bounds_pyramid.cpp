#include "builder/cpvs_bounds_pyramid.hpp"

#include <algorithm>

namespace shadowtiles {
namespace {

CpvsBlockBounds merge(CpvsBlockBounds a, CpvsBlockBounds b) {
  return {std::max(a.max_lit_end, b.max_lit_end), std::min(a.min_shadow_begin, b.min_shadow_begin)};
}

}  // namespace

CpvsBoundsPyramid::CpvsBoundsPyramid(const TileIntervals& intervals, uint32_t depth_steps)
    : intervals_(intervals), depth_steps_(depth_steps), base_side_(std::min<uint32_t>(4, intervals.size)) {
  const uint32_t size = intervals.size;
  if (size == 0) return;
  // Level 0 straight from the texels, then each level from the one below.
  uint32_t blocks = size / base_side_;
  std::vector<CpvsBlockBounds> base(size_t(blocks) * blocks, CpvsBlockBounds{0, depth_steps});
  for (uint32_t v = 0; v < size; ++v)
    for (uint32_t u = 0; u < size; ++u) {
      cpvs::StepBounds t = texel(u, v);
      CpvsBlockBounds& b = base[size_t(v / base_side_) * blocks + u / base_side_];
      b = merge(b, {t.lit_end, t.shadow_begin});
    }
  levels_.push_back(std::move(base));
  while (blocks > 1) {
    const std::vector<CpvsBlockBounds>& below = levels_.back();
    uint32_t half = blocks / 2;
    std::vector<CpvsBlockBounds> level(size_t(half) * half);
    for (uint32_t y = 0; y < half; ++y)
      for (uint32_t x = 0; x < half; ++x) {
        size_t i = size_t(2 * y) * blocks + 2 * x;
        level[size_t(y) * half + x] =
            merge(merge(below[i], below[i + 1]), merge(below[i + blocks], below[i + blocks + 1]));
      }
    levels_.push_back(std::move(level));
    blocks = half;
  }
}

cpvs::StepBounds CpvsBoundsPyramid::texel(uint32_t u, uint32_t v) const {
  if (u >= intervals_.size || v >= intervals_.size) return {0, depth_steps_};
  const DepthInterval& t = intervals_.at(u, v);
  return cpvs::step_bounds(t.lower, t.upper, depth_steps_);
}

CpvsBlockBounds CpvsBoundsPyramid::block(uint32_t side, uint32_t u0, uint32_t v0) const {
  const uint32_t size = intervals_.size;
  if (u0 >= size || v0 >= size) return {0, depth_steps_};  // wholly outside the tile: free
  if (side >= size) return levels_.back()[0];               // covers the whole tile
  if (side < base_side_) {
    CpvsBlockBounds b{0, depth_steps_};
    for (uint32_t v = v0; v < v0 + side; ++v)
      for (uint32_t u = u0; u < u0 + side; ++u) {
        cpvs::StepBounds t = texel(u, v);
        b = merge(b, {t.lit_end, t.shadow_begin});
      }
    return b;
  }
  unsigned level = unsigned(std::countr_zero(side / base_side_));
  uint32_t blocks = size / side;
  return levels_[level][size_t(v0 / side) * blocks + u0 / side];
}

}  // namespace shadowtiles
