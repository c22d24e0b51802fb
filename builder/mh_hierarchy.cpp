#include "builder/mh_hierarchy.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "codec/mh_format.hpp"

namespace shadowtiles {
namespace F = mh_format;

float mh_value_for(const DepthInterval& interval) {
  const float lo = interval.lower, hi = interval.upper;
  if (std::isfinite(lo) && std::isfinite(hi)) return std::clamp(lo + (hi - lo) * 0.5f, lo, hi);
  if (std::isfinite(lo)) return lo;
  if (std::isfinite(hi)) return hi;
  return 1.0f;  // unconstrained: no texel reads this value
}

MhTileSummary summarize(const MhHierarchy& h) { return MhTileSummary{h.root}; }

namespace {

// The expanded tree's size: depth-first over reachable blocks, each block's subtree size memoised
// (shared blocks count once per reference); recursion depth is bounded by `levels`.
struct ExpandedSize {
  const MhHierarchy& h;
  std::vector<uint8_t> seen;
  std::vector<uint64_t> tree_nodes;  // per block: nodes of the expanded subtree below it

  uint64_t visit(uint32_t b) {
    if (seen[b]) return tree_nodes[b];
    seen[b] = 1;
    const uint8_t mask = h.block_mask[b];
    uint64_t total = 0;
    unsigned r = 0;
    for (unsigned i = 0; i < 4; ++i) {
      const unsigned code = F::child_code(mask, i);
      if (code == 0) continue;
      total += 1;
      if (code & 2u) total += visit(h.child_block[h.block_first_child[b] + r++]);
    }
    return tree_nodes[b] = total;
  }
};

// Per block mask: its children of each code, by table. std::popcount is a libgcc call in this
// build (no -mpopcnt), and four per block were 1.8 % of a full-depth build's samples.
struct MaskCounts {
  uint8_t leaves, empty, inner, branching;
};
constexpr std::array<MaskCounts, 256> make_mask_counts() {
  std::array<MaskCounts, 256> table{};
  for (unsigned mask = 0; mask < 256; ++mask)
    for (unsigned i = 0; i < 4; ++i) {
      const unsigned code = F::child_code(uint8_t(mask), i);
      table[mask].leaves += code == F::kCodeLeaf;
      table[mask].empty += code == F::kCodeEmpty;
      table[mask].inner += code == F::kCodeInner;
      table[mask].branching += (code & 2u) != 0;
    }
  return table;
}
constexpr std::array<MaskCounts, 256> kMaskCounts = make_mask_counts();

}  // namespace

MhNodeCounts count_nodes(const MhHierarchy& h) {
  MhNodeCounts counts = count_stored_nodes(h);
  ExpandedSize expanded{h, std::vector<uint8_t>(h.block_count(), 0), std::vector<uint64_t>(h.block_count(), 0)};
  counts.tree_nodes = 1 + (h.root_mask != 0 ? expanded.visit(h.root_block) : 0);
  return counts;
}

MhNodeCounts count_stored_nodes(const MhHierarchy& h) {
  MhNodeCounts counts;
  if (h.root_mask == 0) {
    counts.leaves = 1;
    return counts;
  }
  counts.inner = 1;
  // Breadth-first: on the builder's trees (numbered breadth-first) this reads the blocks in order.
  std::vector<uint8_t> seen(h.block_count(), 0);
  std::vector<uint32_t> queue{h.root_block};
  queue.reserve(h.block_count());
  seen[h.root_block] = 1;
  for (size_t k = 0; k < queue.size(); ++k) {
    const uint32_t b = queue[k];
    counts.blocks += 1;
    const MaskCounts& c = kMaskCounts[h.block_mask[b]];
    counts.leaves += c.leaves;
    counts.empty += c.empty;
    counts.inner += c.inner;
    const uint32_t* child = &h.child_block[h.block_first_child[b]];
    for (unsigned r = 0; r < c.branching; ++r)
      if (!seen[child[r]]) seen[child[r]] = 1, queue.push_back(child[r]);
  }
  return counts;
}

Status check_structure(const MhHierarchy& h) {
  auto fail = [](const std::string& m) { return Status(make_error(ErrorCode::invalid_input, "MH hierarchy: " + m)); };
  if (h.levels > 20 || h.size != (uint32_t(1) << h.levels)) return fail("size is not 2^levels");
  const size_t n = h.block_count();
  if (h.block_first_child.size() != n || h.block_first_value.size() != n) return fail("block arrays differ in size");
  if (h.root_mask != 0 && (h.levels == 0 || h.root_block >= n)) return fail("bad root block");
  // What build_mh and merge_mmh produce (blocks numbered breadth-first): every child has a higher
  // index than its parent, so there is no cycle, and one pass from the last block both validates
  // each block and computes its height from its children's, already known. Only the root's needs
  // checking: a block at depth d below it has height <= root's - d. The depth-first search below
  // handles any other numbering. On a full-depth tree the check is a few % of a build's CPU (run
  // once per encoder), so validation and heights share the pass.
  bool children_after_parents = true;
  std::vector<uint8_t> fast_height(n, 0);
  for (size_t b = n; b-- > 0;) {
    const uint8_t m = h.block_mask[b];
    if (m == 0) return fail("block with no children");
    if (uint64_t(h.block_first_child[b]) + F::branch_children(m) > h.child_block.size() ||
        uint64_t(h.block_first_value[b]) + F::valued_children(m) > h.intervals.size())
      return fail("block entries out of range");
    unsigned hb = 0;
    for (unsigned r = 0; r < F::branch_children(m); ++r) {
      const uint32_t c = h.child_block[h.block_first_child[b] + r];
      if (c >= n) return fail("child block out of range");
      children_after_parents &= c > b;
      hb = std::max(hb, unsigned(fast_height[c]) + 1);  // final only when every child is after b
    }
    fast_height[b] = uint8_t(std::min(hb, 255u));  // beyond 255 is too deep for any level count (<= 20)
  }
  if (children_after_parents) {
    if (h.root_mask == 0) return Status::success();
    if (1 + unsigned(fast_height[h.root_block]) > h.levels) return fail("paths longer than the level count (or a cycle)");
    return Status::success();
  }
  // Heights by memoised depth-first search; a cycle shows up as a path longer than the levels.
  std::vector<int> height(n, -1);
  std::vector<uint8_t> on_path(n, 0);
  bool too_deep = false;
  auto visit = [&](auto&& self, uint32_t b, unsigned depth) -> int {
    if (depth > h.levels || on_path[b]) return too_deep = true, 0;
    if (height[b] >= 0) {
      if (depth + unsigned(height[b]) > h.levels) too_deep = true;
      return height[b];
    }
    on_path[b] = 1;
    int hb = 0;
    const uint8_t m = h.block_mask[b];
    for (unsigned r = 0; r < F::branch_children(m) && !too_deep; ++r)
      hb = std::max(hb, 1 + self(self, h.child_block[h.block_first_child[b] + r], depth + 1));
    on_path[b] = 0;
    if (depth + unsigned(hb) > h.levels) too_deep = true;
    return height[b] = hb;
  };
  if (h.root_mask != 0) visit(visit, h.root_block, 1);
  if (too_deep) return fail("paths longer than the level count (or a cycle)");
  return Status::success();
}

}  // namespace shadowtiles
