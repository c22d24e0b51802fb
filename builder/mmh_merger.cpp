#include "builder/mmh_merger.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <limits>
#include <unordered_map>

#include "codec/mh_format.hpp"
#include "common/huge_page_array.hpp"

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

// A point-like interval intersects another point-like interval only when the two are equal: a
// point [c, c] with c < 1 (every surface hit on an open mesh), or the miss [1, +inf). Its key is the
// point's bit pattern (+0 and -0 alike) or, for the miss, a pattern no float has.
bool point_key(const DepthInterval& x, uint64_t* key) {
  if (x.lower == x.upper && x.lower < 1.0f) {
    const float c = x.lower == 0.0f ? 0.0f : x.lower;
    uint32_t bits;
    std::memcpy(&bits, &c, sizeof bits);
    *key = bits;
    return true;
  }
  if (x.lower == 1.0f && x.upper == kInf) {
    *key = uint64_t(1) << 40;
    return true;
  }
  return false;
}

// Per block, from its children's: what the merge buckets and filters by. Computed in reverse
// breadth-first order (children before parents), a loop where a recursive walk went depth-first
// through memory.
struct BlockSummaries {
  std::vector<uint8_t> height;
  std::vector<uint64_t> hash;       // topology: the masks of the subtree
  std::vector<DepthInterval> hull;  // [min lower, max upper] of the subtree's valued intervals
  // Per block: every valued interval of its subtree is point-like (see point_key), and the hash of
  // those keys in subtree order. Only computed when `points` is set.
  std::vector<uint8_t> point_like;
  std::vector<uint64_t> point_hash;

  BlockSummaries(size_t blocks, bool points)
      : height(blocks, 0), hash(blocks, 0), hull(blocks), point_like(points ? blocks : 0, 0),
        point_hash(points ? blocks : 0, 0) {}

  void summarize(const MhHierarchy& h, uint32_t b) {
    const uint8_t mask = h.block_mask[b];
    uint64_t hb = mix(0x6d68, mask);
    unsigned ht = 0;
    DepthInterval hl{kInf, -kInf};
    const bool index = !point_like.empty();
    bool points = true;
    uint64_t ph = 0x706f;
    for (unsigned v = 0; v < F::valued_children(mask); ++v) {
      const DepthInterval& x = h.intervals[h.block_first_value[b] + v];
      hl.lower = std::min(hl.lower, x.lower), hl.upper = std::max(hl.upper, x.upper);
      uint64_t key = 0;
      if (index && (points = points && point_key(x, &key))) ph = mix(ph, key);
    }
    for (unsigned r = 0; r < F::branch_children(mask); ++r) {
      const uint32_t c = h.child_block[h.block_first_child[b] + r];
      hb = mix(hb, hash[c]);
      ht = std::max(ht, unsigned(height[c]) + 1);
      hl.lower = std::min(hl.lower, hull[c].lower), hl.upper = std::max(hl.upper, hull[c].upper);
      if (index && (points = points && point_like[c])) ph = mix(ph, point_hash[c]);
    }
    hash[b] = hb;
    height[b] = uint8_t(ht);
    hull[b] = hl;
    if (index) point_like[b] = points, point_hash[b] = ph;
  }
};

// The merge's bucket: blocks of one height and topology hash (masked to the options' bits).
uint64_t bucket_key(const BlockSummaries& s, uint32_t b, uint64_t hash_mask) {
  return mix(s.height[b], s.hash[b] & hash_mask);
}
// A point-like block's key in the point index: its bucket and the hash of its values.
uint64_t point_slot_hash(uint64_t bucket, uint64_t point_hash) { return mix(point_hash, bucket); }

// Reachable blocks in breadth-first order from the root; false when a block is referenced twice
// (the input already shares) or the root is referenced.
bool breadth_first_order(const MhHierarchy& h, std::vector<uint32_t>& order,
                         std::vector<uint32_t>* parent_entry) {
  order.clear();
  if (h.root_mask == 0) return true;
  std::vector<uint8_t> seen(parent_entry ? 0 : h.block_count(), 0);
  order.push_back(h.root_block);
  for (size_t k = 0; k < order.size(); ++k) {
    const uint32_t b = order[k];
    for (unsigned r = 0; r < F::branch_children(h.block_mask[b]); ++r) {
      const uint32_t e = h.block_first_child[b] + r, c = h.child_block[e];
      if (c == h.root_block) return false;
      if (parent_entry) {
        if ((*parent_entry)[c] != kNone) return false;
        (*parent_entry)[c] = e;
      } else {
        if (seen[c]) return false;
        seen[c] = 1;
      }
      order.push_back(c);
    }
  }
  return true;
}

// Two bitsets over a key per block, a few bits per block (cache-resident where a table of the keys
// would be tens of MiB): `unique[b]` = 1 proves that no other block of `blocks` has b's key; 0 is a
// key seen twice, shared or a collision. Returns how many blocks got 0.
template <class KeyOf>
size_t mark_unique_keys(const std::vector<uint32_t>& blocks, KeyOf key_of, std::vector<uint8_t>& unique) {
  thread_local std::vector<uint64_t> seen, seen_twice;
  const size_t bits = std::bit_ceil(std::max<size_t>(64, 4 * blocks.size()));
  seen.assign(bits / 64, 0);
  seen_twice.assign(bits / 64, 0);
  auto bit_of = [&](uint32_t b) { return size_t(key_of(b) >> 7) & (bits - 1); };
  for (uint32_t b : blocks) {
    const size_t i = bit_of(b);
    const uint64_t bit = uint64_t(1) << (i % 64);
    seen_twice[i / 64] |= seen[i / 64] & bit;
    seen[i / 64] |= bit;
  }
  size_t repeated = 0;
  for (uint32_t b : blocks) {
    const size_t i = bit_of(b);
    unique[b] = (seen_twice[i / 64] >> (i % 64) & 1) == 0;
    repeated += !unique[b];
  }
  return repeated;
}

struct Merger {
  MhHierarchy& h;
  std::vector<uint8_t> dead;

  uint32_t child(uint32_t b, unsigned r) const { return h.child_block[h.block_first_child[b] + r]; }
  DepthInterval& interval(uint32_t b, unsigned v) { return h.intervals[h.block_first_value[b] + v]; }

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
  // The input's sizes bound the output's: reserved, the arrays are written once instead of grown
  // by doubling (each growth copied them and faulted in fresh pages: 7 % of an MMH build's CPU on a
  // full-depth tree).
  order.reserve(h.block_count());
  out.block_mask.reserve(h.block_count());
  out.block_first_child.reserve(h.block_count());
  out.block_first_value.reserve(h.block_count());
  out.child_block.reserve(h.child_block.size());
  out.intervals.reserve(h.intervals.size());
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
  if (!breadth_first_order(h, order, &parent_entry))
    return make_error(ErrorCode::invalid_input, "MMH merge: input already shares blocks");
  st.blocks_before = order.size();
  if (order.size() <= 1) {
    st.blocks_after = order.size();
    return compact(h);
  }

  const bool index_points = options.index_point_values;
  BlockSummaries summaries(n, index_points);
  for (size_t k = order.size(); k-- > 0;) summaries.summarize(h, order[k]);  // children before parents
  Merger m{h, std::vector<uint8_t>(n, 0)};
  // Tallest first; among equals, breadth-first order.
  // A counting sort: heights are at most the levels (<= 20 here, < 256 by type), and this gives
  // std::stable_sort's order in one pass instead of n log n moves (1.5 % of honolulu's build).
  {
    std::array<size_t, 257> start{};
    for (uint32_t b : order) ++start[255 - summaries.height[b] + 1];
    for (size_t k = 1; k < start.size(); ++k) start[k] += start[k - 1];
    std::vector<uint32_t> sorted(order.size());
    for (uint32_t b : order) sorted[start[255 - summaries.height[b]]++] = b;
    order.swap(sorted);
  }

  const uint64_t hash_mask = options.hash_bits == 64 ? ~uint64_t(0) : (uint64_t(1) << options.hash_bits) - 1;
  // Representatives per bucket as parallel arrays (hull and first interval inline), so the scan of up
  // to max_tests_per_block candidates is a branch-free pass over 64 at a time that the compiler
  // vectorises; only candidates passing both filters pay for the full comparison (which misses the
  // cache). Same candidates, same order (most recent first), same first fit as a one-by-one scan.
  struct Reps {
    std::vector<uint32_t> block;
    std::vector<float> height;  // as float, so the filter loop compares one type
    std::vector<float> hull_lower, hull_upper, first_lower, first_upper;
    // Point index: per rep, the previous rep of this bucket with the same point hash (kNone: none);
    // and the reps that were not point-like when they joined, in order.
    std::vector<uint32_t> previous_same_points;
    std::vector<uint32_t> not_point;
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
  uint64_t last_bucket_key = 0;
  Reps* last_reps = nullptr;
  // (bucket, point hash) -> the bucket's most recent point-like rep with that hash: a flat
  // open-addressing table of 8-byte slots (tag | 1 + point rep id), verified against the point reps'
  // own arrays. std::unordered_map's node per entry, or wider slots, cost more than the scan saves.
  struct PointRep {
    uint64_t bucket;  // bucket key
    uint64_t point_hash;
    uint32_t rep;  // index in its bucket
  };
  std::vector<PointRep> point_reps;
  auto slot_hash = point_slot_hash;
  auto bucket_key_of = [&](uint32_t b) { return bucket_key(summaries, b, hash_mask); };
  // Point-like blocks whose (bucket, point hash) no other block shares can never meet a rep with
  // their key, nor be one another block finds: they skip the table. On a full-depth tree of distinct
  // floats that is most blocks, and each probe was a cache miss (a third of the merge's time). Two
  // bitsets over the key's hash, a few bits per block (cache-resident where the table is tens of
  // MiB), find them: a hash seen twice (a shared key, or a collision) keeps the block in the table.
  // `unique_key[b]`: 1 for those blocks.
  std::vector<uint8_t> unique_key(index_points ? n : 0, 0);
  size_t keyed_blocks = 0;  // point-like blocks that use the table
  if (index_points) {
    std::vector<uint32_t> point_blocks;
    for (uint32_t b : order)
      if (summaries.point_like[b]) point_blocks.push_back(b);
    keyed_blocks = mark_unique_keys(
        point_blocks, [&](uint32_t b) { return slot_hash(bucket_key_of(b), summaries.point_hash[b]); }, unique_key);
  }
  // Reused per thread: a fresh table would pay a page fault per 4 KiB on every tile.
  // In 2 MiB pages where the kernel allows: each probe is a random read of a table of up to tens of
  // MiB, which with 4 KiB pages also missed the TLB.
  thread_local HugePageArray<uint64_t> latest_with_points;
  latest_with_points.assign_zero(index_points ? std::bit_ceil(std::max<size_t>(16, 2 * keyed_blocks)) : 0);
  // The slot for (bucket, point hash): holds its latest point rep, or is the free slot to claim.
  auto latest_slot = [&](uint64_t bucket, uint64_t point_hash) -> uint64_t& {
    const size_t mask = latest_with_points.size() - 1;
    const uint64_t full = slot_hash(bucket, point_hash);
    const uint64_t tag = full >> 32;
    for (size_t i = size_t(full) & mask;; i = (i + 1) & mask) {
      uint64_t& slot = latest_with_points[i];
      if (slot == 0) return slot;
      if ((slot >> 32) != tag) continue;
      const PointRep& r = point_reps[uint32_t(slot) - 1];
      if (r.bucket == bucket && r.point_hash == point_hash) return slot;
    }
  };
  auto slot_rep = [&](uint64_t slot) { return slot == 0 ? kNone : point_reps[uint32_t(slot) - 1].rep; };
  uint64_t scanned = 0;
  constexpr size_t kPrefetchAhead = 16;  // table slots are DRAM misses: fetch them this many blocks early
  for (size_t position = 0; position < order.size(); ++position) {
    const uint32_t b = order[position];
    if (index_points && position + kPrefetchAhead < order.size()) {
      const uint32_t ahead = order[position + kPrefetchAhead];
      if (summaries.point_like[ahead] && !unique_key[ahead])
        __builtin_prefetch(&latest_with_points[slot_hash(bucket_key_of(ahead), summaries.point_hash[ahead]) &
                                               (latest_with_points.size() - 1)]);
    }
    if (m.dead[b] || b == h.root_block) continue;
    const uint64_t bucket_key = bucket_key_of(b);
    // Neighbours in this order mostly share a bucket (a height's full blocks): the last one found is
    // kept (std::unordered_map's nodes do not move), saving a hash lookup per block.
    if (bucket_key != last_bucket_key || !last_reps) last_reps = &buckets[bucket_key], last_bucket_key = bucket_key;
    Reps& reps = *last_reps;
    const DepthInterval first = first_interval(b), hull = summaries.hull[b];
    const float height = summaries.height[b];
    const size_t stop = reps.size() > options.max_tests_per_block ? reps.size() - options.max_tests_per_block : 0;
    auto try_merge = [&](size_t k) {  // full test against rep k; on a fit, b joins it
      ++st.full_tests;
      const Match match = m.compare(b, reps.block[k]);
      if (match == Match::topology) ++st.topology_mismatches;
      if (match != Match::ok) return false;
      m.narrow(reps.block[k], b);
      const DepthInterval narrowed = first_interval(reps.block[k]);
      reps.first_lower[k] = narrowed.lower, reps.first_upper[k] = narrowed.upper;
      h.child_block[parent_entry[b]] = reps.block[k];
      m.kill(b);
      ++st.merges;
      return true;
    };
    bool merged = false;
    const bool point_like = index_points && summaries.point_like[b];
    uint64_t* latest = nullptr;
    if (point_like) {
      // Intervals only shrink under narrowing, so a rep that fits b now fitted b when it joined. A rep
      // that was point-like then fits only blocks with its exact point keys, i.e. its point hash; the
      // others are the reps that were not point-like. Walking both lists most recent first, inside the
      // same window, finds the same first fit as the scan below, without testing the other reps.
      // At most one slot per keyed block: never full. A unique key has no slot and no same-key rep.
      if (!unique_key[b]) latest = &latest_slot(bucket_key, summaries.point_hash[b]);
      uint32_t same = latest ? slot_rep(*latest) : kNone;
      size_t other = reps.not_point.size();
      while (!merged) {
        const bool have_same = same != kNone && same >= stop;
        const bool have_other = other > 0 && reps.not_point[other - 1] >= stop;
        if (!have_same && !have_other) break;
        ++scanned;
        if (have_same && (!have_other || same > reps.not_point[other - 1])) {
          merged = try_merge(same);
          same = reps.previous_same_points[same];
          continue;
        }
        const size_t k = reps.not_point[--other];
        const bool pass = reps.hull_lower[k] <= hull.upper && hull.lower <= reps.hull_upper[k] &&
                          reps.first_lower[k] <= first.upper && first.lower <= reps.first_upper[k] &&
                          reps.height[k] == height;
        if (pass) merged = try_merge(k);
      }
    } else {
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
          if (pass[i] && try_merge(begin + i)) {
            merged = true;
            break;
          }
        }
        end = begin;
      }
    }
    if (merged) continue;
    if (index_points) {
      if (point_like) {
        reps.previous_same_points.push_back(latest ? slot_rep(*latest) : kNone);
        if (latest) {
          point_reps.push_back({bucket_key, summaries.point_hash[b], uint32_t(reps.size())});
          *latest = (slot_hash(bucket_key, summaries.point_hash[b]) >> 32) << 32 | uint64_t(point_reps.size());
        }
      } else {
        reps.previous_same_points.push_back(kNone);
        reps.not_point.push_back(uint32_t(reps.size()));
      }
    }
    reps.push(b, height, hull, first);
  }
  st.hull_rejections = scanned - st.full_tests;  // includes the rare bucket-key collisions across heights
  MhHierarchy out = compact(h);
  st.blocks_after = out.block_count();
  return out;
}

bool mmh_merge_finds_nothing(const MhHierarchy& tree) {
  // Two blocks merge only when their topology is the same and every pair of intervals intersects,
  // which point-like intervals do only when equal. Blocks that fit have children that fit, down to
  // a pair of blocks without branch children ("leaf blocks"), distinct when the tree shares
  // nothing. So: every block point-like and no two leaf blocks equal (mask and values) proves
  // that nothing merges. A block with a wider interval may fit blocks of other values: only the
  // merge can tell. Blocks are read in index order (build_mh's is breadth-first), unreachable ones
  // too (one more condition each), so that a tile that merges says so before the structure checks.
  const size_t n = tree.block_count();
  if (tree.block_first_value.size() != n) return false;
  std::vector<uint64_t> leaf_keys;
  leaf_keys.reserve(n);
  // The last leaf keys seen, direct-mapped: equal blocks lie near each other in breadth-first order
  // (a flat roof's rows), so a tile that merges usually says so here, before the bitsets and sort.
  constexpr unsigned kRecentBits = 12;
  std::array<uint64_t, size_t(1) << kRecentBits> recent{};
  for (uint32_t b = 0; b < n; ++b) {
    if (b == tree.root_block && tree.root_mask != 0) continue;  // never merged, never a representative
    const uint8_t mask = tree.block_mask[b];
    const size_t first = tree.block_first_value[b];
    if (first + F::valued_children(mask) > tree.intervals.size()) return false;  // malformed
    uint64_t key = 0x9e3779b97f4a7c15ull * (uint64_t(mask) + 1);
    for (unsigned v = 0; v < F::valued_children(mask); ++v) {
      uint64_t point = 0;
      if (!point_key(tree.intervals[first + v], &point)) return false;
      key = (key ^ point) * 0xbf58476d1ce4e5b9ull;
    }
    if (F::branch_children(mask) != 0) continue;
    key = mix(key, 0) | 1;  // never 0, the empty slot
    uint64_t& slot = recent[key >> (64 - kRecentBits)];
    if (slot == key) return false;  // equal keys: perhaps equal blocks
    slot = key;
    leaf_keys.push_back(key);
  }
  std::vector<uint32_t> order;
  if (!check_structure(tree) || !breadth_first_order(tree, order, nullptr)) return false;  // or shared
  std::vector<uint32_t> leaves(leaf_keys.size());
  for (uint32_t i = 0; i < leaves.size(); ++i) leaves[i] = i;
  std::vector<uint8_t> unique(leaves.size(), 0);
  if (mark_unique_keys(leaves, [&](uint32_t i) { return leaf_keys[i]; }, unique) == 0) return true;
  std::vector<uint64_t> repeated;  // the bitsets' maybes, settled exactly (equal keys: maybe equal)
  for (uint32_t i : leaves)
    if (!unique[i]) repeated.push_back(leaf_keys[i]);
  std::sort(repeated.begin(), repeated.end());
  return std::adjacent_find(repeated.begin(), repeated.end()) == repeated.end();
}

}  // namespace shadowtiles
