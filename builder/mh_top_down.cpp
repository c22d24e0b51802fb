#include "builder/mh_top_down.hpp"

#include <algorithm>
#include <bit>

#include "builder/mh_dense_levels.hpp"

namespace shadowtiles {
namespace {

struct TopDown {
  const TileIntervals& tile;
  MhDenseLevels& dense;
  std::vector<DepthInterval> region;  // scratch: the texels of the current node
  std::vector<float> lowers, uppers;  // scratch for the sweep

  void gather(unsigned level, uint64_t p) {
    const unsigned shift = dense.levels - level;
    const uint32_t side = uint32_t(1) << shift;
    const uint32_t x0 = morton_x(p) << shift, y0 = morton_y(p) << shift;
    region.clear();
    for (uint32_t y = y0; y < y0 + side; ++y)
      region.insert(region.end(), &tile.at(x0, y), &tile.at(x0, y) + side);
  }

  size_t coverage(float value) const {
    size_t n = 0;
    for (const DepthInterval& t : region) n += t.contains(value);
    return n;
  }

  // Sweep over sorted endpoints: the maximum overlap is reached at some lower bound.
  float best_value(size_t* best_count) {
    lowers.clear();
    uppers.clear();
    for (const DepthInterval& t : region) lowers.push_back(t.lower), uppers.push_back(t.upper);
    std::sort(lowers.begin(), lowers.end());
    std::sort(uppers.begin(), uppers.end());
    size_t best = 0, ended = 0;
    float value = lowers[0];
    for (size_t i = 0; i < lowers.size(); ++i) {
      if (i + 1 < lowers.size() && lowers[i + 1] == lowers[i]) continue;  // count all equal starts
      while (ended < uppers.size() && uppers[ended] < lowers[i]) ++ended;
      const size_t count = i + 1 - ended;
      if (count > best) best = count, value = lowers[i];
    }
    *best_count = best;
    return value;
  }

  // Returns the node's code as seen by its parent.
  unsigned build(unsigned level, uint64_t p, float inherited, bool has_inherited) {
    gather(level, p);
    const size_t inherited_count = has_inherited ? coverage(inherited) : 0;
    if (has_inherited && inherited_count == region.size()) return 0;  // all covered: absent
    size_t best_count;
    const float best = best_value(&best_count);
    const bool valued = !has_inherited || best_count > inherited_count;
    const float value = valued ? best : inherited;
    uint8_t mask = 0;
    if (level < dense.levels) {
      for (unsigned i = 0; i < 4; ++i) mask |= uint8_t(build(level + 1, 4 * p + i, value, true) << (2 * i));
      dense.masks[level][p] = mask;
    }
    return (valued ? 1u : 0u) | (mask ? 2u : 0u);
  }
};

}  // namespace

MhHierarchy build_mh_top_down(const TileIntervals& tile) {
  MhDenseLevels dense;
  dense.size = tile.size;
  dense.levels = unsigned(std::countr_zero(tile.size));
  dense.masks.resize(dense.levels);
  for (unsigned l = 0; l < dense.levels; ++l) dense.masks[l].assign(size_t(1) << (2 * l), 0);
  TopDown builder{tile, dense, {}, {}, {}};
  builder.build(0, 0, 0.0f, false);
  compute_validity(tile, dense);
  return to_hierarchy(std::move(dense));
}

}  // namespace shadowtiles
