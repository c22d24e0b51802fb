#include "builder/mh_dense_levels.hpp"

#include <algorithm>
#include <cassert>
#include <limits>

#include "codec/mh_format.hpp"

namespace shadowtiles {
namespace F = mh_format;

namespace {
constexpr float kInf = std::numeric_limits<float>::infinity();
inline void intersect(DepthInterval& a, const DepthInterval& b) {
  a.lower = std::max(a.lower, b.lower);
  a.upper = std::min(a.upper, b.upper);
}
}  // namespace

void compute_validity(const TileIntervals& tile, MhDenseLevels& dense) {
  const unsigned L = dense.levels;
  dense.valued.assign(L + 1, {});
  // resolve[p] at level l: intersection of the texels below p that resolve to p or above it.
  std::vector<DepthInterval> child, parent;
  if (L == 0) {
    dense.valued[0] = {tile.texels[0]};
    return;
  }
  for (unsigned l = L; l-- > 0;) {
    const size_t n = size_t(1) << (2 * l);
    const bool bottom = l + 1 == L;
    parent.assign(n, DepthInterval{-kInf, kInf});
    auto& masks = dense.masks[l];
    auto& valued = dense.valued[l + 1];
    for (size_t p = 0; p < n; ++p) {
      uint8_t mask = masks[p];
      for (unsigned i = 0; i < 4; ++i) {
        const size_t c = 4 * p + i;
        const DepthInterval r = bottom ? tile.at(morton_x(c), morton_y(c)) : child[c];
        unsigned code = F::child_code(mask, i);
        if ((code & 1u) && r.lower == -kInf && r.upper == kInf) {
          assert(code == F::kCodeInner);  // a valued leaf always resolves its own texels
          code = F::kCodeEmpty;
          mask = uint8_t((mask & ~(3u << (2 * i))) | (code << (2 * i)));
        }
        if (code & 1u)
          valued.push_back(r);
        else
          intersect(parent[p], r);
      }
      masks[p] = mask;
    }
    child.swap(parent);
  }
  dense.valued[0] = {child[0]};
}

MhHierarchy to_hierarchy(MhDenseLevels&& dense) {
  MhHierarchy h;
  h.size = dense.size;
  h.levels = dense.levels;
  h.root = dense.valued[0].at(0);
  h.root_mask = dense.levels ? dense.masks[0][0] : 0;
  h.root_block = 0;
  // Branch nodes in breadth-first order are the blocks; the k-th entry with children therefore
  // owns block k + 1 (block 0 holds the root's children).
  uint32_t values = 0;
  for (unsigned l = 0; l < dense.levels; ++l) {
    for (uint8_t mask : dense.masks[l]) {
      if (mask == 0) continue;
      h.block_mask.push_back(mask);
      h.block_first_child.push_back(uint32_t(h.child_block.size()));
      h.block_first_value.push_back(values);
      for (unsigned r = 0; r < F::branch_children(mask); ++r) h.child_block.push_back(uint32_t(h.child_block.size() + 1));
      values += F::valued_children(mask);
    }
    std::vector<uint8_t>().swap(dense.masks[l]);
  }
  h.intervals.reserve(values);
  for (unsigned l = 1; l <= dense.levels; ++l) {
    h.intervals.insert(h.intervals.end(), dense.valued[l].begin(), dense.valued[l].end());
    std::vector<DepthInterval>().swap(dense.valued[l]);
  }
  assert(h.intervals.size() == values);
  assert(h.child_block.size() + 1 == h.block_mask.size() || (h.block_mask.empty() && h.child_block.empty()));
  return h;
}

}  // namespace shadowtiles
