#include "builder/mmh_merger.hpp"

#include <algorithm>
#include <limits>
#include <unordered_map>

#include "codec/mh_format.hpp"

namespace shadowtiles {
namespace F = mh_format;

namespace {

constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();
constexpr float kInf = std::numeric_limits<float>::infinity();

uint64_t mix(uint64_t h, uint64_t x) {  // splitmix64 finaliser over a running combination
  uint64_t z = h ^ (x + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2));
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

enum class Match { ok, topology, intervals };

struct Merger {
  MhHierarchy& h;
  std::vector<uint8_t> height;
  std::vector<uint64_t> hash;
  std::vector<DepthInterval> hull;  // [min lower, max upper] of the subtree's valued intervals
  std::vector<uint8_t> dead;

  uint32_t child(uint32_t b, unsigned r) const { return h.child_block[h.block_first_child[b] + r]; }
  DepthInterval& interval(uint32_t b, unsigned v) { return h.intervals[h.block_first_value[b] + v]; }

  void summarize(uint32_t b) {  // recursion depth bounded by the levels (check_structure)
    const uint8_t mask = h.block_mask[b];
    uint64_t hb = mix(0x6d68, mask);
    unsigned ht = 0;
    DepthInterval hl{kInf, -kInf};
    for (unsigned v = 0; v < F::valued_children(mask); ++v)
      hl.lower = std::min(hl.lower, interval(b, v).lower), hl.upper = std::max(hl.upper, interval(b, v).upper);
    for (unsigned r = 0; r < F::branch_children(mask); ++r) {
      const uint32_t c = child(b, r);
      summarize(c);
      hb = mix(hb, hash[c]);
      ht = std::max(ht, unsigned(height[c]) + 1);
      hl.lower = std::min(hl.lower, hull[c].lower), hl.upper = std::max(hl.upper, hull[c].upper);
    }
    hash[b] = hb;
    height[b] = uint8_t(ht);
    hull[b] = hl;
  }

  Match compare(uint32_t a, uint32_t r) {
    const uint8_t mask = h.block_mask[a];
    if (mask != h.block_mask[r]) return Match::topology;
    Match result = Match::ok;
    for (unsigned v = 0; v < F::valued_children(mask); ++v) {
      const DepthInterval &x = interval(a, v), &y = interval(r, v);
      if (!(x.lower <= y.upper && y.lower <= x.upper)) result = Match::intervals;
    }
    for (unsigned k = 0; k < F::branch_children(mask); ++k) {
      const Match m = compare(child(a, k), child(r, k));
      if (m == Match::topology) return m;  // report collisions even after an interval mismatch
      if (m == Match::intervals) result = m;
    }
    return result;
  }

  void narrow(uint32_t r, uint32_t a) {
    const uint8_t mask = h.block_mask[r];
    for (unsigned v = 0; v < F::valued_children(mask); ++v) {
      DepthInterval& y = interval(r, v);
      const DepthInterval& x = interval(a, v);
      y.lower = std::max(y.lower, x.lower);
      y.upper = std::min(y.upper, x.upper);
    }
    for (unsigned k = 0; k < F::branch_children(mask); ++k) narrow(child(r, k), child(a, k));
  }

  void kill(uint32_t b) {
    dead[b] = 1;
    for (unsigned r = 0; r < F::branch_children(h.block_mask[b]); ++r) kill(child(b, r));
  }
};

// Reachable blocks renumbered in breadth-first order; intervals copied per block.
MhHierarchy compact(const MhHierarchy& h) {
  MhHierarchy out;
  out.size = h.size;
  out.levels = h.levels;
  out.root = h.root;
  out.root_mask = h.root_mask;
  out.root_block = 0;
  if (h.root_mask == 0) return out;
  std::vector<uint32_t> id(h.block_count(), kNone), order{h.root_block};
  id[h.root_block] = 0;
  for (size_t k = 0; k < order.size(); ++k) {
    const uint32_t b = order[k];
    const uint8_t mask = h.block_mask[b];
    out.block_mask.push_back(mask);
    out.block_first_child.push_back(uint32_t(out.child_block.size()));
    out.block_first_value.push_back(uint32_t(out.intervals.size()));
    for (unsigned r = 0; r < F::branch_children(mask); ++r) {
      const uint32_t c = h.child_block[h.block_first_child[b] + r];
      if (id[c] == kNone) id[c] = uint32_t(order.size()), order.push_back(c);
      out.child_block.push_back(id[c]);
    }
    for (unsigned v = 0; v < F::valued_children(mask); ++v)
      out.intervals.push_back(h.intervals[h.block_first_value[b] + v]);
  }
  return out;
}

}  // namespace

Result<MhHierarchy> merge_mmh(const MhHierarchy& tree, const MmhMergeOptions& options, MmhMergeStats* stats) {
  if (Status s = check_structure(tree); !s) return s.error();
  if (options.hash_bits < 1 || options.hash_bits > 64)
    return make_error(ErrorCode::invalid_input, "MMH merge: hash_bits must be in [1, 64]");
  MmhMergeStats local;
  MmhMergeStats& st = stats ? *stats : local;
  st = MmhMergeStats{};
  MhHierarchy h = tree;
  const size_t n = h.block_count();

  // Parent entry of every reachable block; a second reference means the input already shares.
  std::vector<uint32_t> parent_entry(n, kNone), order;
  if (h.root_mask != 0) {
    order.push_back(h.root_block);
    for (size_t k = 0; k < order.size(); ++k) {
      const uint32_t b = order[k];
      for (unsigned r = 0; r < F::branch_children(h.block_mask[b]); ++r) {
        const uint32_t e = h.block_first_child[b] + r, c = h.child_block[e];
        if (parent_entry[c] != kNone || c == h.root_block)
          return make_error(ErrorCode::invalid_input, "MMH merge: input already shares blocks");
        parent_entry[c] = e;
        order.push_back(c);
      }
    }
  }
  st.blocks_before = order.size();
  if (order.size() <= 1) {
    st.blocks_after = order.size();
    return compact(h);
  }

  Merger m{h, std::vector<uint8_t>(n, 0), std::vector<uint64_t>(n, 0), std::vector<DepthInterval>(n),
           std::vector<uint8_t>(n, 0)};
  m.summarize(h.root_block);
  // Tallest first; among equals, breadth-first order.
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return m.height[a] > m.height[b]; });

  const uint64_t hash_mask = options.hash_bits == 64 ? ~uint64_t(0) : (uint64_t(1) << options.hash_bits) - 1;
  // Representatives per bucket as parallel arrays (hull and first interval inline), so the scan of up
  // to max_tests_per_block candidates is a branch-free pass over 64 at a time that the compiler
  // vectorises; only candidates passing both filters pay for the full comparison (which misses the
  // cache). Same candidates, same order (most recent first), same first fit as a one-by-one scan.
  struct Reps {
    std::vector<uint32_t> block;
    std::vector<float> height;  // as float, so the filter loop compares one type
    std::vector<float> hull_lower, hull_upper, first_lower, first_upper;
    size_t size() const { return block.size(); }
    void push(uint32_t b, float ht, const DepthInterval& hull, const DepthInterval& first) {
      block.push_back(b), height.push_back(ht);
      hull_lower.push_back(hull.lower), hull_upper.push_back(hull.upper);
      first_lower.push_back(first.lower), first_upper.push_back(first.upper);
    }
  };
  auto first_interval = [&](uint32_t b) {  // interval of the first valued node in b's subtree
    while (F::valued_children(h.block_mask[b]) == 0) b = m.child(b, 0);
    return m.interval(b, 0);
  };
  std::unordered_map<uint64_t, Reps> buckets;
  uint64_t scanned = 0;
  for (const uint32_t b : order) {
    if (m.dead[b] || b == h.root_block) continue;
    Reps& reps = buckets[mix(m.height[b], m.hash[b] & hash_mask)];
    const DepthInterval first = first_interval(b), hull = m.hull[b];
    const float height = m.height[b];
    const size_t stop = reps.size() > options.max_tests_per_block ? reps.size() - options.max_tests_per_block : 0;
    bool merged = false;
    for (size_t end = reps.size(); end > stop && !merged;) {
      const size_t begin = std::max(stop, end >= 64 ? end - 64 : size_t(0));
      // pass[i]: candidate begin + i passes the filters (intersecting hulls and first intervals; same
      // height: bucket keys may collide across heights).
      const size_t count = end - begin;
      const float* hl = reps.hull_lower.data() + begin;
      const float* hu = reps.hull_upper.data() + begin;
      const float* fl = reps.first_lower.data() + begin;
      const float* fu = reps.first_upper.data() + begin;
      const float* ht = reps.height.data() + begin;
      alignas(64) int32_t pass[64];
      for (size_t k = 0; k < count; ++k)  // float compares only, no branches: this loop vectorises
        pass[k] = (hl[k] <= hull.upper) & (hull.lower <= hu[k]) & (fl[k] <= first.upper) &
                  (first.lower <= fu[k]) & (ht[k] == height);
      scanned += count;
      for (size_t i = count; i-- > 0;) {  // most recent first
        if (!pass[i]) continue;
        const size_t k = begin + i;
        ++st.full_tests;
        const Match match = m.compare(b, reps.block[k]);
        if (match == Match::topology) ++st.topology_mismatches;
        if (match != Match::ok) continue;
        m.narrow(reps.block[k], b);
        const DepthInterval narrowed = first_interval(reps.block[k]);
        reps.first_lower[k] = narrowed.lower, reps.first_upper[k] = narrowed.upper;
        h.child_block[parent_entry[b]] = reps.block[k];
        m.kill(b);
        ++st.merges;
        merged = true;
        break;
      }
      end = begin;
    }
    if (!merged) reps.push(b, height, hull, first);
  }
  st.hull_rejections = scanned - st.full_tests;  // includes the rare bucket-key collisions across heights
  MhHierarchy out = compact(h);
  st.blocks_after = out.block_count();
  return out;
}

}  // namespace shadowtiles
