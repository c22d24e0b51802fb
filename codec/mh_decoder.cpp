#include "codec/mh_decoder.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstring>
#include <string>

#include "codec/mh_format.hpp"
#include "codec/skip_cell_parts.hpp"
#include "common/byte_order.hpp"

namespace shadowtiles {
using namespace bytes;  // payload field loads (common/byte_order.hpp)
namespace {

namespace F = mh_format;

// Per mask: how many children have records, and each child's rank among records / values, so a
// step is two table reads instead of bit counting.
struct MaskInfo {
  uint8_t records;
  uint8_t record_rank[4];
  uint8_t value_rank[4];
};

constexpr std::array<MaskInfo, 256> make_mask_info() {
  std::array<MaskInfo, 256> table{};
  for (unsigned mask = 0; mask < 256; ++mask) {
    MaskInfo info{};
    uint8_t records = 0, values = 0;
    for (unsigned i = 0; i < 4; ++i) {
      info.record_rank[i] = records;
      info.value_rank[i] = values;
      unsigned code = F::child_code(uint8_t(mask), i);
      records += (code >> 1) & 1;
      values += code & 1;
    }
    info.records = records;
    table[mask] = info;
  }
  return table;
}
constexpr std::array<MaskInfo, 256> kMaskInfo = make_mask_info();

template <unsigned W>
inline uint32_t load_offset(const uint8_t* p) {
  if constexpr (W == 3) {
    // Two loads and a shift: a 3-byte memcpy into a zeroed word went through the stack, and the
    // word's load waited on the two partial stores (a tenth of the parse on 14 MB tiles, whose
    // offsets are 3 bytes wide; the walks' steps read them too).
    uint16_t low;
    std::memcpy(&low, p, 2);
    return uint32_t(low) | uint32_t(p[2]) << 16;
  } else {
    uint32_t x = 0;
    std::memcpy(&x, p, W);
    return x;
  }
}
// Runtime width (parse): one fixed-size read per case. A memcpy of runtime length compiled to
// `rep movsb`, whose start-up cost made it a quarter of the parse (fzk_haus 16384² `anywhere`).
inline uint32_t load_offset(const uint8_t* p, unsigned width) {
  switch (width) {
    case 1: return load_offset<1>(p);
    case 2: return load_offset<2>(p);
    case 3: return load_offset<3>(p);
    default: return load_offset<4>(p);
  }
}

inline unsigned child_index(uint32_t u, uint32_t v, unsigned shift) {
  return ((u >> shift) & 1u) | (((v >> shift) & 1u) << 1);
}

// One step from a node (value, mask, offset) to its child i. Returns false when the child is absent
// (the walk ends at the current node). A leaf child is entered with mask = 0.
template <unsigned W, class State>
inline bool step(const uint8_t* stream, unsigned i, State& s) {
  const unsigned code = F::child_code(s.mask, i);
  if (code == 0) return false;
  const MaskInfo& info = kMaskInfo[s.mask];
  const uint8_t* block = stream + s.offset;
  if (code & 1u) s.value = load_f32(block + info.records * (1 + W) + 4 * info.value_rank[i]);
  if (code & 2u) {
    const uint8_t* record = block + info.record_rank[i] * (1 + W);
    s.mask = record[0];
    s.offset = load_offset<W>(record + 1);
  } else {
    s.mask = 0;
    s.offset = 0;
  }
  return true;
}

// Walks from `s` at `level` toward (u, v) down to `stop_level`; returns the level reached.
template <unsigned W, class State>
inline unsigned walk(const uint8_t* stream, State& s, unsigned level, unsigned stop_level, unsigned levels,
                     uint32_t u, uint32_t v) {
  while (s.mask != 0 && level < stop_level) {
    if (!step<W>(stream, child_index(u, v, levels - 1 - level), s)) break;
    ++level;
  }
  return level;
}

Error corrupt(const std::string& what) { return make_error(ErrorCode::corrupt_data, "MH payload: " + what); }

}  // namespace

Result<MhTileView> MhTileView::parse(std::span<const uint8_t> payload, const MhParseOptions& options) {
  const uint8_t* h = payload.data();
  if (payload.size() < F::kHeaderBytes) return corrupt("shorter than its header");
  if (std::memcmp(h + F::kOffMagic, F::kMagic, 4) != 0) return corrupt("bad magic");
  const uint16_t version = load_u16(h + F::kOffVersion);
  if (version > F::kFormatVersion)
    return make_error(ErrorCode::unsupported, "MH payload format version " + std::to_string(version) +
                                                  " is newer than this decoder (" +
                                                  std::to_string(F::kFormatVersion) + ")");
  if (version != F::kFormatVersion) return corrupt("bad format version " + std::to_string(version));
  const uint16_t flags = load_u16(h + F::kOffFlags);
  if (flags & ~F::kKnownFlags) return corrupt("unknown flags");

  MhTileView view;
  view.size_ = load_u32(h + F::kOffSize);
  view.levels_ = h[F::kOffLevels];
  view.offset_width_ = h[F::kOffOffsetWidth];
  const unsigned embedded_skip = h[F::kOffSkipLevel];
  view.root_mask_ = h[F::kOffRootMask];
  view.root_value_ = load_f32(h + F::kOffRootValue);
  view.root_block_ = load_u32(h + F::kOffRootBlock);
  const uint32_t stream_bytes = load_u32(h + F::kOffStreamBytes);
  const uint32_t block_count = load_u32(h + F::kOffBlockCount);
  const uint32_t record_count = load_u32(h + F::kOffRecordCount);
  const uint32_t value_count = load_u32(h + F::kOffValueCount);
  const unsigned L = view.levels_, W = view.offset_width_;

  if (L > F::kMaxLevels || view.size_ != (uint32_t(1) << L)) return corrupt("bad size or level count");
  if (W < 1 || W > 4) return corrupt("bad offset width");
  const bool has_skip = flags & F::kFlagSkipList;
  if (has_skip ? (embedded_skip < 1 || embedded_skip > std::min(L, F::kMaxSkipLevel)) : embedded_skip != 0)
    return corrupt("bad skip list level");
  if (!std::isfinite(view.root_value_)) return corrupt("non-finite root value");
  if (L == 0 && view.root_mask_ != 0) return corrupt("a 1x1 tile cannot have children");
  if (view.root_mask_ == 0 && (view.root_block_ != 0 || stream_bytes != 0))
    return corrupt("leaf root with a node stream");
  const uint64_t skip_bytes = has_skip ? (uint64_t(1) << (2 * embedded_skip)) * F::skip_entry_bytes(W) : 0;
  if (uint64_t(payload.size()) != F::kHeaderBytes + skip_bytes + stream_bytes)
    return corrupt("size " + std::to_string(payload.size()) + " does not match its header");
  view.stream_ = h + F::kHeaderBytes + skip_bytes;

  MhStats& st = view.stats_;
  st.size = view.size_;
  st.levels = L;
  st.merged = flags & F::kFlagMerged;
  st.offset_width = W;
  st.skip_level = embedded_skip;
  st.payload_bytes = payload.size();
  st.header_bytes = F::kHeaderBytes;
  st.skip_list_bytes = skip_bytes;
  st.stream_bytes = stream_bytes;
  (view.root_mask_ ? st.inner_nodes : st.leaf_nodes) += 1;

  // Blocks must tile the stream exactly from offset 0 and every reference must point forward, so
  // the block graph is acyclic and every byte is accounted for. One scan in offset order checks it:
  // a block's mask is in its parents' records, and its parents lie before it, so when the scan
  // reaches an offset every reference to it has been read (`mask_at`, one byte per stream byte).
  // A heap of pending references did the same in O(n log n): 18 % of a full-depth build's CPU
  // (fzk_haus 16384², `anywhere`; every payload is parsed back for its preview).
  if (view.root_mask_ != 0) {
    const uint8_t* stream = view.stream_;
    const size_t R = F::record_bytes(W);
    if (view.root_block_ != 0)
      return corrupt("blocks overlap or leave a gap at offset " + std::to_string(view.root_block_));
    if (stream_bytes == 0) return corrupt("block runs past the node stream");
    std::vector<uint8_t> mask_at(stream_bytes, 0);  // 0: no reference (a referenced mask is never 0)
    mask_at[0] = view.root_mask_;
    uint64_t referenced = 1;  // distinct offsets referenced, the root's included
    struct Block {
      uint32_t offset;
      uint8_t mask;
    };
    std::vector<Block> blocks;
    blocks.reserve(block_count <= stream_bytes / 2 ? block_count : 0);  // a corrupt count reserves nothing
    uint64_t records = 0, values = 0;
    for (uint64_t offset = 0; offset < stream_bytes;) {
      const uint8_t mask = mask_at[offset];
      if (mask == 0) return corrupt("blocks overlap or leave a gap at offset " + std::to_string(offset));
      const size_t bytes = F::block_bytes(mask, W);
      if (offset + bytes > stream_bytes) return corrupt("block runs past the node stream");
      const MaskInfo& info = kMaskInfo[mask];
      for (unsigned i = 0; i < 4; ++i) {
        const unsigned code = F::child_code(mask, i);
        if (code & 2u) {
          const uint8_t* record = stream + offset + info.record_rank[i] * R;
          const uint8_t child_mask = record[0];
          const uint32_t target = load_offset(record + 1, W);
          if (child_mask == 0) return corrupt("node with children has an empty mask");
          if (uint64_t(target) < offset + bytes || target >= stream_bytes)
            return corrupt("block offset out of range or not forward");
          if (mask_at[target] == 0) {
            mask_at[target] = child_mask;
            ++referenced;
          } else if (mask_at[target] != child_mask) {
            return corrupt("a shared block is referenced with different masks");
          }
          (code & 1u ? st.inner_nodes : st.empty_nodes) += 1;
        } else if (code & 1u) {
          st.leaf_nodes += 1;
        }
        if (code & 1u) {
          if (!std::isfinite(load_f32(stream + offset + info.records * R + 4 * info.value_rank[i])))
            return corrupt("non-finite value");
        }
      }
      records += info.records;
      values += F::valued_children(mask);
      blocks.push_back({uint32_t(offset), mask});
      offset += bytes;
    }
    // A referenced offset the scan stepped over lies inside another block.
    if (referenced != blocks.size()) return corrupt("a reference points inside a block (blocks overlap)");
    if (blocks.size() != block_count || records != record_count || values != value_count)
      return corrupt("node counts do not match the header");
    st.blocks = blocks.size();
    st.block_references = 1 + records;  // the root's and every record's

    // Heights in reverse offset order (children lie at higher offsets): the deepest node must not
    // go below the texel level, which bounds every walk by the level count. A block's entry of
    // `mask_at` is read for the last time just before it is overwritten with the block's height, so
    // the entries of its children, all after it, already hold theirs (every reference is a block
    // start: the count above).
    std::vector<uint8_t>& height_at = mask_at;
    for (size_t b = blocks.size(); b-- > 0;) {
      const Block& block = blocks[b];
      const MaskInfo& info = kMaskInfo[block.mask];
      unsigned hb = 0;
      for (unsigned r = 0; r < info.records; ++r)
        hb = std::max(hb, unsigned(height_at[load_offset(stream + block.offset + r * R + 1, W)]) + 1);
      if (hb + 1 > L) return corrupt("tree deeper than the tile's level count");
      height_at[block.offset] = uint8_t(hb);
    }
  } else if (block_count != 0 || record_count != 0 || value_count != 0) {
    return corrupt("node counts do not match the header");
  }

  // Skip list: derived from the tree; an embedded one must equal it byte for byte.
  unsigned S = has_skip ? embedded_skip : std::min({options.skip_level, L, F::kMaxSkipLevel});
  if (!has_skip && options.skip_level == kMhSkipLevelBySize)
    while (S > 0 && (sizeof(WalkState) << (2 * S)) * 5 > payload.size()) --S;
  if (S > 0) {
    const uint32_t side = uint32_t(1) << S;
    view.skip_level_ = S;
    view.skip_.resize(size_t(side) * side);
    const uint8_t* stored = h + F::kHeaderBytes;
    const size_t entry_bytes = F::skip_entry_bytes(W);
    for (uint32_t y = 0; y < side; ++y) {
      for (uint32_t x = 0; x < side; ++x) {
        WalkState s{view.root_value_, view.root_block_, view.root_mask_};
        const uint32_t u = x << (L - S), v = y << (L - S);
        unsigned level = 0;
        switch (W) {
          case 1: level = walk<1>(view.stream_, s, 0, S, L, u, v); break;
          case 2: level = walk<2>(view.stream_, s, 0, S, L, u, v); break;
          case 3: level = walk<3>(view.stream_, s, 0, S, L, u, v); break;
          default: level = walk<4>(view.stream_, s, 0, S, L, u, v); break;
        }
        if (level < S) s.mask = 0, s.offset = 0;  // the walk ended above S: the value decides
        if (s.mask == 0) s.offset = 0;
        view.skip_[size_t(y) * side + x] = s;
        if (has_skip) {
          const uint8_t* e = stored + (size_t(y) * side + x) * entry_bytes;
          const float stored_value = load_f32(e);
          if (std::memcmp(&stored_value, &s.value, 4) != 0 || e[4] != s.mask || load_offset(e + 5, W) != s.offset)
            return corrupt("skip list does not match the tree");
        }
      }
    }
  }
  return view;
}

MhTileView::WalkState MhTileView::start_state(uint32_t u, uint32_t v, unsigned stop, unsigned* level) const {
  if (skip_level_ != 0 && stop >= skip_level_) {
    *level = skip_level_;
    return skip_[skip_index(u, v)];
  }
  *level = 0;
  return WalkState{root_value_, root_block_, root_mask_};
}

float MhTileView::lookup(uint32_t u, uint32_t v, unsigned max_level) const {
  assert(u < size_ && v < size_);
  u &= size_ - 1;
  v &= size_ - 1;
  const unsigned stop = std::min(max_level, levels_);
  unsigned level;
  WalkState s = start_state(u, v, stop, &level);
  switch (offset_width_) {
    case 1: walk<1>(stream_, s, level, stop, levels_, u, v); break;
    case 2: walk<2>(stream_, s, level, stop, levels_, u, v); break;
    case 3: walk<3>(stream_, s, level, stop, levels_, u, v); break;
    case 4: walk<4>(stream_, s, level, stop, levels_, u, v); break;
    default: break;  // default-constructed view: root value only
  }
  return s.value;
}

template <unsigned W>
uint32_t MhTileView::count_from_ancestor(WalkState s, unsigned lca, uint32_t u0, uint32_t v0, uint32_t kw, uint32_t kh,
                                         float depth, float bias) const {
  const uint32_t u1 = u0 + kw - 1, v1 = v0 + kh - 1;
  const unsigned L = levels_;
  WalkState path[F::kMaxLevels + 1];
  path[lca] = s;
  unsigned end = lca;
  uint32_t pu = u0, pv = v0, lit = 0;
  // Samples go by the 2x2 squares of their parents (raster order of the squares): the samples of one
  // parent follow each other and share its walk. A 3x3 kernel in a full-depth tree steps ~18 times
  // this way, ~22 in raster order.
  for (uint32_t sv = v0 & ~1u; sv <= v1; sv += 2) {
    for (uint32_t su = u0 & ~1u; su <= u1; su += 2) {
      for (uint32_t v = std::max(sv, v0); v <= std::min(sv + 1, v1); ++v) {
        for (uint32_t u = std::max(su, u0); u <= std::min(su + 1, u1); ++u) {
          // Resume from the deepest node this sample shares with the previous one.
          const unsigned shared = L - unsigned(std::bit_width((u ^ pu) | (v ^ pv)));
          unsigned from = std::min(shared, end);
          WalkState c = path[from];
          while (c.mask != 0 && from < L) {
            if (!step<W>(stream_, child_index(u, v, L - 1 - from), c)) break;
            path[++from] = c;
          }
          end = from;
          lit += depth <= c.value + bias;
          pu = u;
          pv = v;
        }
      }
    }
  }
  return lit;
}

template <unsigned W>
uint32_t MhTileView::pcf_count_impl(uint32_t u0, uint32_t v0, uint32_t kw, uint32_t kh, float depth,
                                    float bias) const {
  const uint32_t u1 = u0 + kw - 1, v1 = v0 + kh - 1;
  const unsigned L = levels_;
  const unsigned lca = L - unsigned(std::bit_width((u0 ^ u1) | (v0 ^ v1)));
  if (skip_level_ != 0 && lca < skip_level_) {
    // Across skip list cells: each part from its own entry (codec/skip_cell_parts.hpp); in preorder
    // the upper levels' blocks lie far apart, so every step down to the list's level would miss.
    return sum_over_skip_cell_parts(u0, v0, u1, v1, L - skip_level_,
                                    [&](uint32_t pu0, uint32_t pv0, uint32_t pu1, uint32_t pv1) {
                                      return pcf_count_impl<W>(pu0, pv0, pu1 - pu0 + 1, pv1 - pv0 + 1, depth, bias);
                                    });
  }
  unsigned level;
  WalkState s = start_state(u0, v0, lca, &level);
  level = walk<W>(stream_, s, level, lca, L, u0, v0);
  // The walk ended above the kernel's common ancestor (or at a leaf there): one value decides all.
  if (level < lca || s.mask == 0) return depth <= s.value + bias ? kw * kh : 0;
  return count_from_ancestor<W>(s, lca, u0, v0, kw, kh, depth, bias);
}

template <unsigned W>
void MhTileView::pcf_count_sorted_impl(std::span<const TexelQuery> corners, uint32_t k, uint32_t* counts) const {
  const unsigned L = levels_;
  WalkState path[F::kMaxLevels + 1];  // path[base..end]: the previous box's walk toward its corner
  unsigned base = 0, end = 0;
  bool have_path = false;  // false until a box has walked (boxes answered in parts do not)
  uint32_t pu = 0, pv = 0;
  for (size_t i = 0; i < corners.size(); ++i) {
    const uint32_t u0 = corners[i].u, v0 = corners[i].v, u1 = u0 + k - 1, v1 = v0 + k - 1;
    const float depth = corners[i].threshold;
    const unsigned lca = L - unsigned(std::bit_width((u0 ^ u1) | (v0 ^ v1)));
    if (skip_level_ != 0 && lca < skip_level_) {
      // Across skip list cells: in parts, each from its entry (pcf_count_impl). The path kept for
      // the next box stays that of the last box that walked.
      counts[i] = pcf_count_impl<W>(u0, v0, k, k, depth, 0.0f);
      continue;
    }
    const unsigned shared = L - unsigned(std::bit_width((u0 ^ pu) | (v0 ^ pv)));
    unsigned level;
    WalkState s;
    if (have_path && shared >= base && lca >= base) {
      // Nodes down to `shared` lie on both corners' paths; the walk toward this corner goes on from there.
      level = std::min({shared, end, lca});
      s = path[level];
    } else {
      s = start_state(u0, v0, lca, &level);
      base = level;
      path[level] = s;
      have_path = true;
    }
    while (s.mask != 0 && level < lca) {
      if (!step<W>(stream_, child_index(u0, v0, L - 1 - level), s)) break;
      path[++level] = s;
    }
    end = level;
    pu = u0;
    pv = v0;
    // As pcf_count_impl: a walk ending above the common ancestor (or at a leaf there) decides all.
    counts[i] = level < lca || s.mask == 0 ? (depth <= s.value + 0.0f ? k * k : 0)
                                           : count_from_ancestor<W>(s, lca, u0, v0, k, k, depth, 0.0f);
  }
}

void MhTileView::pcf_count_sorted(std::span<const TexelQuery> corners, uint32_t k, uint32_t* counts) const {
  for (const TexelQuery& c : corners) {
    assert(k >= 1 && c.u < size_ && c.v < size_ && k <= size_ - c.u && k <= size_ - c.v);
    if (k == 0 || c.u >= size_ || c.v >= size_ || k > size_ - c.u || k > size_ - c.v) {
      // Release builds: out-of-contract boxes answer as pcf_lit_count does (clamped), one by one.
      for (size_t i = 0; i < corners.size(); ++i)
        counts[i] = pcf_lit_count(corners[i].u, corners[i].v, k, k, corners[i].threshold, 0.0f);
      return;
    }
  }
  switch (offset_width_) {
    case 1: return pcf_count_sorted_impl<1>(corners, k, counts);
    case 2: return pcf_count_sorted_impl<2>(corners, k, counts);
    case 3: return pcf_count_sorted_impl<3>(corners, k, counts);
    case 4: return pcf_count_sorted_impl<4>(corners, k, counts);
    default:  // default-constructed view: nothing stored
      for (size_t i = 0; i < corners.size(); ++i) counts[i] = 0;
  }
}

uint32_t MhTileView::pcf_lit_count(uint32_t u0, uint32_t v0, uint32_t kw, uint32_t kh, float depth,
                                   float bias) const {
  assert(kw >= 1 && kh >= 1 && u0 < size_ && v0 < size_ && kw <= size_ - u0 && kh <= size_ - v0);
  if (size_ == 0 || u0 >= size_ || v0 >= size_) return 0;
  kw = std::min(kw, size_ - u0);
  kh = std::min(kh, size_ - v0);
  if (kw == 0 || kh == 0) return 0;
  switch (offset_width_) {
    case 1: return pcf_count_impl<1>(u0, v0, kw, kh, depth, bias);
    case 2: return pcf_count_impl<2>(u0, v0, kw, kh, depth, bias);
    case 3: return pcf_count_impl<3>(u0, v0, kw, kh, depth, bias);
    case 4: return pcf_count_impl<4>(u0, v0, kw, kh, depth, bias);
    default: return 0;
  }
}

// Skip lists from this level on (768 KiB and more) are read ahead by the interleaved batch walks.
constexpr unsigned kPrefetchedSkipLevel = 8;

template <unsigned W>
void MhTileView::lit_interleaved_impl(std::span<const TexelQuery> queries, unsigned stop, uint8_t* lit) const {
  // Independent walks, one level at a time in turn, each prefetching its next block: the misses of
  // kLanes walks overlap instead of following one another.
  constexpr unsigned kLanes = 8;
  const unsigned L = levels_;
  const uint32_t mask = size_ - 1;
  struct Lane {
    WalkState s;
    unsigned level;
    uint32_t u, v;
    size_t index;
    bool entering;  // its skip list entry is being fetched: read on the lane's next turn
  };
  Lane lanes[kLanes];
  size_t next = 0;
  auto prefetch = [&](const WalkState& s) {
    if (s.mask == 0) return;
    __builtin_prefetch(stream_ + s.offset);
    __builtin_prefetch(stream_ + s.offset + F::block_bytes(s.mask, W) - 1);
  };
  // A deep skip list (large tiles: level 8, 768 KiB) is itself a miss per walk: its entry is
  // prefetched here and read a turn later, like the blocks. A small one stays in cache, where
  // that extra turn per walk would only cost (fzk_haus 16384^2 surfaces, level 5: batch -5%).
  const bool skip_entry = skip_level_ >= kPrefetchedSkipLevel && stop >= skip_level_;
  auto start = [&](Lane& lane) {
    lane.index = next++;
    lane.u = queries[lane.index].u & mask;
    lane.v = queries[lane.index].v & mask;
    lane.entering = skip_entry;
    if (skip_entry) {
      __builtin_prefetch(&skip_[skip_index(lane.u, lane.v)]);
      return;
    }
    lane.s = start_state(lane.u, lane.v, stop, &lane.level);
    prefetch(lane.s);
  };
  unsigned live = 0;
  for (; live < kLanes && next < queries.size(); ++live) start(lanes[live]);
  while (live > 0) {
    for (unsigned i = 0; i < live;) {
      Lane& lane = lanes[i];
      if (lane.entering) {
        lane.entering = false;
        lane.s = start_state(lane.u, lane.v, stop, &lane.level);
        prefetch(lane.s);
        ++i;
        continue;
      }
      if (lane.s.mask != 0 && lane.level < stop &&
          step<W>(stream_, child_index(lane.u, lane.v, L - 1 - lane.level), lane.s)) {
        ++lane.level;
        prefetch(lane.s);
        ++i;
        continue;
      }
      lit[lane.index] = queries[lane.index].threshold <= lane.s.value;
      if (next < queries.size()) {
        start(lane);
        ++i;
      } else {
        lane = lanes[--live];  // the last live lane takes this slot (visited next)
      }
    }
  }
}

template <unsigned W>
void MhTileView::lit_sorted_impl(std::span<const TexelQuery> queries, unsigned stop, uint8_t* lit) const {
  const unsigned L = levels_;
  const uint32_t mask = size_ - 1;
  WalkState path[F::kMaxLevels + 1];
  unsigned base = 0, end = 0;  // path[base..end] holds the previous query's walk
  uint32_t pu = 0, pv = 0;
  for (size_t i = 0; i < queries.size(); ++i) {
    const uint32_t u = queries[i].u & mask, v = queries[i].v & mask;
    const unsigned shared = L - unsigned(std::bit_width((u ^ pu) | (v ^ pv)));
    unsigned from;
    WalkState c;
    if (i > 0 && shared >= base) {
      from = std::min(shared, end);
      c = path[from];
    } else {
      c = start_state(u, v, stop, &from);
      base = from;
      path[from] = c;
    }
    while (c.mask != 0 && from < stop) {
      if (!step<W>(stream_, child_index(u, v, L - 1 - from), c)) break;
      path[++from] = c;
    }
    end = from;
    lit[i] = queries[i].threshold <= c.value;
    pu = u;
    pv = v;
  }
}

bool MhTileView::sparse_queries(std::span<const TexelQuery> queries, unsigned stop) const {
  // Sparse: most neighbours along the curve share no node within 2 levels of the walks' end, so
  // resuming from a shared node saves little and interleaving independent walks overlaps misses.
  // (fzk_haus 16384² under anywhere, 1M shuffled points: 5.9 -> 6.8 M/s on 1 thread, 11.9 -> 12.9 on 2;
  // nefertiti, whose walks are short, unchanged.)
  if (queries.size() < 16 || stop < 4 + skip_level_) return false;
  const unsigned L = levels_;
  const uint32_t mask = size_ - 1;
  size_t close = 0;
  for (size_t i = 1; i < queries.size(); ++i) {
    const uint32_t du = (queries[i].u ^ queries[i - 1].u) & mask, dv = (queries[i].v ^ queries[i - 1].v) & mask;
    close += L - unsigned(std::bit_width(du | dv)) + 2 >= stop;
  }
  return close * 2 < queries.size();
}

void MhTileView::lit_sorted(std::span<const TexelQuery> queries, unsigned max_level, uint8_t* lit) const {
  const unsigned stop = std::min(max_level, levels_);
  if (offset_width_ >= 1 && offset_width_ <= 4 && sparse_queries(queries, stop)) {
    switch (offset_width_) {
      case 1: return lit_interleaved_impl<1>(queries, stop, lit);
      case 2: return lit_interleaved_impl<2>(queries, stop, lit);
      case 3: return lit_interleaved_impl<3>(queries, stop, lit);
      default: return lit_interleaved_impl<4>(queries, stop, lit);
    }
  }
  switch (offset_width_) {
    case 1: return lit_sorted_impl<1>(queries, stop, lit);
    case 2: return lit_sorted_impl<2>(queries, stop, lit);
    case 3: return lit_sorted_impl<3>(queries, stop, lit);
    case 4: return lit_sorted_impl<4>(queries, stop, lit);
    default:  // default-constructed view: root value only
      for (size_t i = 0; i < queries.size(); ++i) lit[i] = queries[i].threshold <= root_value_;
  }
}

float MhTileView::pcf_lit_fraction(uint32_t u0, uint32_t v0, uint32_t k, float depth, float bias) const {
  if (k == 0) return 0.0f;
  return float(pcf_lit_count(u0, v0, k, k, depth, bias)) / float(uint64_t(k) * k);
}

}  // namespace shadowtiles
