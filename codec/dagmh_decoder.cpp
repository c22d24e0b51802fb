#include "codec/dagmh_decoder.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstring>
#include <string>

#include "codec/dagmh_format.hpp"
#include "codec/dagmh_reads.hpp"
#include "codec/skip_cell_parts.hpp"
#include "common/byte_order.hpp"
#include "common/isa_clones.hpp"

namespace shadowtiles {
using namespace bytes;        // payload field loads (common/byte_order.hpp)
using namespace dagmh_reads;  // the payload's other reads (codec/dagmh_reads.hpp)
namespace {

namespace F = dagmh_format;

Error corrupt(const std::string& what) { return make_error(ErrorCode::corrupt_data, "DAG-MH payload: " + what); }

// Depth of every bit of a treelet layout with H levels (pre-order).
void bit_depths(unsigned H, unsigned depth, uint32_t index, std::vector<uint8_t>& out) {
  out[index] = uint8_t(depth);
  if (depth + 1 >= H) return;
  for (unsigned c = 0; c < 4; ++c) bit_depths(H, depth + 1, index + 1 + c * F::complete_nodes(H - 1 - depth), out);
}

}  // namespace

Result<DagMhTileView> DagMhTileView::parse(std::span<const uint8_t> payload, const DagMhParseOptions& options) {
  const uint8_t* h = payload.data();
  if (payload.size() < F::kHeaderBytes) return corrupt("shorter than its header");
  if (std::memcmp(h + F::kOffMagic, F::kMagic, 4) != 0) return corrupt("bad magic");
  const uint32_t version = load_uint(h + F::kOffVersion, 2);
  if (version > F::kFormatVersion)
    return make_error(ErrorCode::unsupported, "DAG-MH payload format version " + std::to_string(version) +
                                                  " is newer than this decoder");
  if (version != F::kFormatVersion) return corrupt("bad format version");
  if (load_uint(h + F::kOffFlags, 2) != 0) return corrupt("unknown flags");

  DagMhTileView view;
  view.size_ = load_uint(h + F::kOffSize, 4);
  view.levels_ = h[F::kOffLevels];
  view.H_ = h[F::kOffTreeletHeight];
  view.wr_ = h[F::kOffRefWidth];
  view.wc_ = h[F::kOffCountWidth];
  view.wo_ = h[F::kOffChunkOffsetWidth];
  view.root_kind_ = h[F::kOffRootKind];
  view.chunk_size_ = load_uint(h + F::kOffChunkSize, 2);
  view.root_ref_ = load_uint(h + F::kOffRootRef, 4);
  const uint32_t dag_bytes = load_uint(h + F::kOffDagBytes, 4);
  const uint32_t treelet_count = load_uint(h + F::kOffTreeletCount, 4);
  view.value_count_ = load_uint(h + F::kOffValueCount, 4);
  const uint32_t chunk_bytes = load_uint(h + F::kOffChunkBytes, 4);
  const unsigned L = view.levels_, H = view.H_, wr = view.wr_, wc = view.wc_, wo = view.wo_;
  const unsigned C = view.chunk_size_;
  const uint32_t N = view.value_count_;

  if (L > F::kMaxLevels || view.size_ != (uint32_t(1) << L)) return corrupt("bad size or level count");
  if (H < F::kMinTreeletHeight || H > F::kMaxTreeletHeight) return corrupt("bad treelet height");
  if (wr < 1 || wr > 4 || wc < 1 || wc > 4 || wo < 1 || wo > 4) return corrupt("bad field width");
  if (C < 1 || C > F::kMaxChunkSize) return corrupt("bad chunk size");
  view.chunk_shift_ = std::has_single_bit(C) ? uint8_t(std::countr_zero(C)) : uint8_t(0xff);
  if (N < 1) return corrupt("no values");
  view.treelet_bytes_ = F::treelet_bytes(H);
  const uint64_t chunk_count = (uint64_t(N) + C - 1) / C;
  const uint64_t treelet_section = uint64_t(treelet_count) * view.treelet_bytes_;
  const uint64_t expected =
      F::kHeaderBytes + uint64_t(dag_bytes) + treelet_section + chunk_count * wo + uint64_t(chunk_bytes);
  if (uint64_t(payload.size()) != expected) return corrupt("size does not match its header");
  view.dag_ = h + F::kHeaderBytes;
  view.treelets_ = view.dag_ + dag_bytes;
  view.chunk_table_ = view.treelets_ + treelet_section;
  view.chunks_ = view.chunk_table_ + chunk_count * wo;

  DagMhStats& st = view.stats_;
  st.size = view.size_;
  st.levels = L;
  st.treelet_height = H;
  st.chunk_size = C;
  st.ref_width = wr;
  st.count_width = wc;
  st.chunk_offset_width = wo;
  st.payload_bytes = payload.size();
  st.header_bytes = F::kHeaderBytes;
  st.dag_bytes = dag_bytes;
  st.treelet_bytes = treelet_section;
  st.treelets = treelet_count;
  st.chunk_table_bytes = chunk_count * wo;
  st.values = N;
  st.chunks = chunk_count;

  // Treelets: value count and height (levels down to the deepest set bit); padding bits zero.
  const size_t TB = view.treelet_bytes_;
  const unsigned bits = unsigned(F::treelet_bits(H));
  std::vector<uint8_t> depth_of(bits, 0);
  bit_depths(H, 0, 0, depth_of);
  std::vector<uint32_t> t_values(treelet_count);
  std::vector<uint8_t> t_height(treelet_count);
  for (uint32_t t = 0; t < treelet_count; ++t) {
    const uint8_t* p = view.treelets_ + size_t(t) * TB;
    if (bits % 8 != 0 && (p[TB - 1] >> (bits % 8)) != 0) return corrupt("treelet padding bits set");
    unsigned count = 0, height = 1;
    for (unsigned b = 0; b < bits; ++b)
      if ((p[b / 8] >> (b % 8)) & 1u) ++count, height = std::max(height, unsigned(depth_of[b]) + 1);
    t_values[t] = count;
    t_height[t] = uint8_t(height);
  }
  // DAG nodes tile their section in order; references point forward to node starts or to treelets.
  std::vector<uint32_t> starts;
  for (uint64_t at = 0; at < dag_bytes;) {
    const uint8_t mask = view.dag_[at];
    if (at + 2 > dag_bytes) return corrupt("DAG node runs past its section");
    if (mask == 0) return corrupt("DAG node without children");
    if (view.dag_[at + 1] > 1) return corrupt("unknown DAG node flags");
    const size_t nb = F::node_bytes(mask, wr, wc);
    if (at + nb > dag_bytes) return corrupt("DAG node runs past its section");
    starts.push_back(uint32_t(at));
    st.dag_mask_bytes += 2;
    st.dag_ref_bytes += F::ref_children(mask) * wr;
    st.dag_count_bytes += nb - 2 - F::ref_children(mask) * wr;
    at += nb;
  }
  st.dag_nodes = starts.size();
  std::vector<uint64_t> n_values(starts.size());
  std::vector<uint8_t> n_height(starts.size());
  for (size_t k = starts.size(); k-- > 0;) {
    const uint8_t* node = view.dag_ + starts[k];
    const uint8_t mask = node[0];
    const unsigned valued = node[1] & 1u;
    const uint8_t* refs = node + 2;
    const uint8_t* counts = refs + F::ref_children(mask) * wr;
    uint64_t sum = 0;
    unsigned height = 1, r = 0, present = 0;
    for (unsigned i = 0; i < 4; ++i) {
      const unsigned code = F::child_code(mask, i);
      if (code == 0) continue;
      if (present > 0 && load_uint(counts + (present - 1) * wc, wc) != sum)
        return corrupt("stored value count does not match the subtree");
      ++present;
      uint64_t child_values = 1;
      unsigned child_height = 1;
      if (code == F::kCodeTreelet) {
        const uint32_t t = load_uint(refs + wr * r++, wr);
        if (t >= treelet_count) return corrupt("treelet reference out of range");
        child_values = t_values[t];
        child_height = t_height[t];
      } else if (code == F::kCodeDag) {
        const uint32_t target = load_uint(refs + wr * r++, wr);
        auto it = std::lower_bound(starts.begin() + k + 1, starts.end(), target);
        if (target <= starts[k] || it == starts.end() || *it != target)
          return corrupt("DAG reference not forward to a node");
        child_values = n_values[it - starts.begin()];
        child_height = n_height[it - starts.begin()];
      }
      sum += child_values;
      height = std::max(height, child_height + 1);
    }
    n_values[k] = sum + valued;
    if (n_values[k] > N) return corrupt("subtree holds more values than the tile");
    if (height > L + 1) return corrupt("tree deeper than the tile's level count");
    n_height[k] = uint8_t(height);
  }

  // Root.
  uint64_t root_values = 0;
  unsigned root_height = 1;
  switch (view.root_kind_) {
    case F::kCodeLeaf:
      if (view.root_ref_ != 0 || dag_bytes != 0) return corrupt("leaf root with a DAG");
      root_values = 1;
      break;
    case F::kCodeTreelet:
      if (dag_bytes != 0 || view.root_ref_ >= treelet_count) return corrupt("bad treelet root");
      if ((view.treelets_[size_t(view.root_ref_) * TB] & 1u) == 0) return corrupt("root without a value");
      root_values = t_values[view.root_ref_];
      root_height = t_height[view.root_ref_];
      break;
    case F::kCodeDag:
      if (dag_bytes == 0 || view.root_ref_ != 0) return corrupt("bad DAG root");
      if ((view.dag_[1] & 1u) == 0) return corrupt("root without a value");
      root_values = n_values[0];
      root_height = n_height[0];
      break;
    default: return corrupt("bad root kind");
  }
  if (root_values != N) return corrupt("value count does not match the tree");
  if (root_height > L + 1) return corrupt("tree deeper than the tile's level count");

  // Chunks: offsets increasing from 0, each chunk exactly its computed size, all values finite.
  view.payload_end_ = h + payload.size();
  for (uint64_t c = 0; c < chunk_count; ++c) {
    const uint64_t begin = load_uint(view.chunk_table_ + c * wo, wo);
    const uint64_t end = c + 1 < chunk_count ? load_uint(view.chunk_table_ + (c + 1) * wo, wo) : chunk_bytes;
    if ((c == 0 && begin != 0) || end < begin || end > chunk_bytes) return corrupt("bad chunk offsets");
    const uint64_t size = end - begin;
    const uint8_t* p = view.chunks_ + begin;
    const unsigned n = unsigned(std::min<uint64_t>(C, N - c * C));
    if (size < 5) return corrupt("chunk too short");
    if (!std::isfinite(load_f32(p))) return corrupt("non-finite representative");
    const unsigned b = p[4];
    if (b == 0) {
      if (size != 5) return corrupt("bad chunk size");
      st.chunk_header_bytes += 5;
      st.representative_bytes += 5;
      st.representative_values += n;
      continue;
    }
    const size_t bm = F::bitmap_bytes(n);
    if (size < 5 + bm) return corrupt("chunk too short");
    if (n % 8 != 0 && (p[5 + bm - 1] >> (n % 8)) != 0) return corrupt("chunk bitmap padding set");
    const unsigned k = popcount_below(p + 5, unsigned(bm * 8));
    st.representative_values += n - k;
    if (b == F::kRawBits) {
      if (size != 5 + bm + 4 * uint64_t(k)) return corrupt("bad chunk size");
      for (unsigned i = 0; i < k; ++i)
        if (!std::isfinite(load_f32(p + 5 + bm + 4 * i))) return corrupt("non-finite value");
      st.chunk_header_bytes += 5 + bm;
      st.representative_bytes += 5;
      st.bitmap_bytes += bm;
      st.raw_value_bytes += 4 * uint64_t(k);
      st.raw_values += k;
    } else if (b <= F::kMaxQuantBits) {
      const uint64_t data = (uint64_t(k) * b + 7) / 8;
      if (size != 5 + bm + 8 + data) return corrupt("bad chunk size");
      const float cl = load_f32(p + 5 + bm), cf = load_f32(p + 5 + bm + 4);
      // Monotone in m: both ends finite means every multiplier decodes to a finite value.
      if (!std::isfinite(cl) || !std::isfinite(cf) || !std::isfinite(F::dequantize(cl, cf, 0)) ||
          !std::isfinite(F::dequantize(cl, cf, (uint32_t(1) << b) - 1)))
        return corrupt("non-finite quantisation grid");
      st.chunk_header_bytes += 5 + bm + 8;
      st.representative_bytes += 5;
      st.bitmap_bytes += bm;
      st.grid_bytes += 8;
      st.multiplier_bytes += data;
      st.quantized_values += k;
    } else {
      return corrupt("bad multiplier width");
    }
  }

  // Skip list, derived. Its entries cost sizeof(State) beside the payload: at most an eighth of the
  // payload, so a small tile is not dominated by its skip list (at 4096^2 in 2048^2 tiles, 64 KiB of
  // level-6 entries per tile made decoded DAG-MH tiles 4.1x their payload). Lookups start higher there.
  unsigned S = std::min({options.skip_level, L, 10u});
  while (S > 0 && (sizeof(State) << (2 * S)) * 8 > payload.size()) --S;
  if (S > 0) {
    const uint32_t side = uint32_t(1) << S;
    view.skip_level_ = S;
    view.skip_.resize(size_t(side) * side);
    for (uint32_t y = 0; y < side; ++y)
      for (uint32_t x = 0; x < side; ++x) {
        State s = view.root_state();
        const uint32_t u = x << (L - S), v = y << (L - S);
        while (s.kind == kDag && s.level < S) view.step(s, u, v);
        view.skip_[size_t(y) * side + x] = s;
      }
  }
  return view;
}

DagMhTileView::State DagMhTileView::root_state() const {
  if (root_kind_ == F::kCodeDag) return State{root_ref_, 0, 0, kDag, 0};
  if (root_kind_ == F::kCodeTreelet) return State{root_ref_, 0, 0, kTreelet, 0};
  return State{0, 0, 0, kDone, 0};
}

DagMhTileView::State DagMhTileView::start_state(uint32_t u, uint32_t v, unsigned stop) const {
  if (skip_level_ != 0 && stop >= skip_level_) {
    const unsigned shift = levels_ - skip_level_;
    return skip_[(size_t(v >> shift) << skip_level_) | (u >> shift)];
  }
  return root_state();
}

// The hot helpers are inlined into each walk (they are called per level and per query).
[[gnu::always_inline]] inline void DagMhTileView::step(State& s, uint32_t u, uint32_t v) const {
  const uint8_t* node = dag_ + s.ref;
  const uint8_t mask = node[0];
  const unsigned i = child_index(u, v, levels_ - 1 - s.level);
  const unsigned code = F::child_code(mask, i);
  if (code == F::kCodeAbsent) {
    s.kind = kDone;
    return;
  }
  const MaskInfo& info = kMaskInfo[mask];
  const unsigned rank = info.present_before[i];
  const uint8_t* counts = node + 2 + info.refs * wr_;
  const uint32_t base = s.count + (node[1] & 1u) + (rank ? load_uint(counts + (rank - 1) * wc_, wc_) : 0);
  if (code == F::kCodeLeaf) {
    s.kind = kDone;
    s.last = base;
    return;
  }
  s.ref = load_uint(node + 2 + info.refs_before[i] * wr_, wr_);
  s.count = base;
  s.level = uint8_t(s.level + 1);
  if (code == F::kCodeTreelet) {
    s.kind = kTreelet;
  } else {
    s.kind = kDag;
    if (dag_[s.ref + 1] & 1u) s.last = base;
  }
}

// Whether node `bit` of the treelet at `t` holds a value, and if so its rank among the treelet's
// valued nodes (set bits before it). The bitmap is read in place as little-endian 64-bit words: bits
// at or past the treelet's end (the next treelet's, the chunk table's) never count, since only bits
// below a node's bit are ranked and every node's bit lies inside the treelet.
[[gnu::always_inline]] inline bool DagMhTileView::treelet_bit(const uint8_t* t, uint32_t bit, uint32_t* rank) const {
  const uint64_t x = load_u64_before(t + 8 * (bit / 64), payload_end_);
  if (!((x >> (bit % 64)) & 1u)) return false;
  unsigned r = popcount64(x & low_bits(bit % 64));
  for (unsigned w = 0; w < bit / 64; ++w) r += popcount64(load_u64_before(t + 8 * w, payload_end_));
  *rank = r;
  return true;
}

// The treelet's part of the walk toward (u, v) down to level `lca` (at or below the treelet's root):
// the node there and the deepest valued node on the way, finest first (s.last when none). A PCF box
// inside one treelet, `lca` its common ancestor, shares this part among all its samples.
[[gnu::always_inline]] inline DagMhTileView::TreeletPrefix DagMhTileView::treelet_prefix(const State& s, uint32_t u,
                                                                                         uint32_t v,
                                                                                         unsigned lca) const {
  TreeletPrefix p;
  p.d = std::min(H_ - 1, levels_ - s.level);
  p.split = std::min(lca - s.level, p.d);
  const uint8_t* t = treelets_ + size_t(s.ref) * treelet_bytes_;
  uint32_t idx[F::kMaxTreeletHeight];
  idx[0] = 0;
  for (unsigned n = 0; n < p.split; ++n)
    idx[n + 1] = idx[n] + 1 + child_index(u, v, levels_ - 1 - (s.level + n)) * F::complete_nodes(H_ - 1 - n);
  p.node = idx[p.split];
  p.result = s.last;
  uint32_t rank;
  for (unsigned n = p.split + 1; n-- > 0;)
    if (treelet_bit(t, idx[n], &rank)) {
      p.result = s.count + rank;
      break;
    }
  return p;
}

// The walk to level `stop` inside the treelet: the prefix down to `stop` is the whole walk.
[[gnu::always_inline]] inline uint32_t DagMhTileView::treelet_find(const State& s, uint32_t u, uint32_t v,
                                                                   unsigned stop) const {
  return treelet_prefix(s, u, v, stop).result;
}

// treelet_find(s, u, v, levels()) for a sample of the box `p` was made for: only the levels below
// the common ancestor are walked.
[[gnu::always_inline]] inline uint32_t DagMhTileView::treelet_find_below(const State& s, uint32_t u, uint32_t v,
                                                                         const TreeletPrefix& p) const {
  const uint8_t* t = treelets_ + size_t(s.ref) * treelet_bytes_;
  uint32_t idx[F::kMaxTreeletHeight];
  idx[p.split] = p.node;
  for (unsigned n = p.split; n < p.d; ++n)
    idx[n + 1] = idx[n] + 1 + child_index(u, v, levels_ - 1 - (s.level + n)) * F::complete_nodes(H_ - 1 - n);
  uint32_t rank;
  for (unsigned n = p.d; n > p.split; --n)
    if (treelet_bit(t, idx[n], &rank)) return s.count + rank;
  return p.result;
}

[[gnu::always_inline]] inline uint32_t DagMhTileView::resolve(State s, uint32_t u, uint32_t v, unsigned stop) const {
  while (s.kind == kDag && s.level < stop) step(s, u, v);
  if (s.kind == kTreelet) return treelet_find(s, u, v, stop);
  return s.last;
}

float DagMhTileView::value_at(uint32_t index) const { return value_of(index); }

// The chunk holding value `index`, clamped as value_of clamps it (for the prefetches below).
[[gnu::always_inline]] inline uint32_t DagMhTileView::chunk_of(uint32_t index) const {
  if (index >= value_count_) index = value_count_ - 1;
  return chunk_shift_ != 0xff ? index >> chunk_shift_ : index / chunk_size_;
}

// Start the fetches value_of(index) waits on, one after the other: its chunk-table entry, then
// (once that entry has arrived) the chunk's header and bitmap.
[[gnu::always_inline]] inline void DagMhTileView::prefetch_chunk_entry(uint32_t index) const {
  if (chunks_ != nullptr) __builtin_prefetch(chunk_table_ + size_t(chunk_of(index)) * wo_);
}
[[gnu::always_inline]] inline void DagMhTileView::prefetch_chunk(uint32_t index) const {
  if (chunks_ != nullptr) __builtin_prefetch(chunks_ + load_uint(chunk_table_ + size_t(chunk_of(index)) * wo_, wo_));
}

[[gnu::always_inline]] inline float DagMhTileView::value_of(uint32_t index) const {
  if (chunks_ == nullptr) return 1.0f;  // default-constructed view
  if (index >= value_count_) index = value_count_ - 1;
  // Chunk sizes are powers of two in practice (the encoder's default is 32): a shift, not a divide.
  const uint32_t c = chunk_shift_ != 0xff ? index >> chunk_shift_ : index / chunk_size_;
  const uint32_t j = index - c * chunk_size_;
  const uint8_t* p = chunks_ + load_uint(chunk_table_ + size_t(c) * wo_, wo_);
  const float rep = load_f32(p);
  const unsigned b = p[4];
  if (b == 0 || ((p[5 + j / 8] >> (j % 8)) & 1u) == 0) return rep;
  const unsigned n = std::min(chunk_size_, value_count_ - c * chunk_size_);
  const size_t bm = F::bitmap_bytes(n);
  // Rank of value j among the differing ones: word popcounts (bits past j are masked off; reads
  // stop at the payload's end).
  const uint8_t* bitmap = p + 5;
  unsigned rank = popcount64(load_u64_before(bitmap + 8 * (j / 64), payload_end_) & low_bits(j % 64));
  for (unsigned w = 0; w < j / 64; ++w) rank += popcount64(load_u64_before(bitmap + 8 * w, payload_end_));
  if (b == F::kRawBits) return load_f32(p + 5 + bm + 4 * size_t(rank));
  const float cl = load_f32(p + 5 + bm), cf = load_f32(p + 5 + bm + 4);
  const uint8_t* data = p + 5 + bm + 8;
  const uint64_t bit = uint64_t(rank) * b;
  // b <= 24 and bit % 8 < 8: the multiplier lies within the 8 bytes from bit / 8.
  const uint64_t acc = load_u64_before(data + bit / 8, payload_end_);
  const uint32_t m = uint32_t((acc >> (bit % 8)) & ((uint64_t(1) << b) - 1));
  return F::dequantize(cl, cf, m);
}

SHADOWTILES_ISA_CLONES float DagMhTileView::lookup(uint32_t u, uint32_t v, unsigned max_level) const {
  assert(u < size_ && v < size_);
  if (size_ == 0) return 1.0f;
  u &= size_ - 1;
  v &= size_ - 1;
  const unsigned stop = std::min(max_level, levels_);
  return value_of(resolve(start_state(u, v, stop), u, v, stop));
}

SHADOWTILES_ISA_CLONES void DagMhTileView::lit_sorted(std::span<const TexelQuery> queries, unsigned max_level,
                                                          uint8_t* lit) const {
  if (size_ == 0) {
    for (size_t i = 0; i < queries.size(); ++i) lit[i] = queries[i].threshold <= 1.0f;
    return;
  }
  const unsigned L = levels_;
  const unsigned stop = std::min(max_level, L);
  const uint32_t mask = size_ - 1;
  State path[F::kMaxLevels + 1];
  unsigned base = 0, end = 0;  // path[base..end] holds the previous query's walk
  uint32_t pu = 0, pv = 0, cached_index = UINT32_MAX;
  float cached_value = 0;
  for (size_t i = 0; i < queries.size(); ++i) {
    const uint32_t u = queries[i].u & mask, v = queries[i].v & mask;
    const unsigned shared = L - unsigned(std::bit_width((u ^ pu) | (v ^ pv)));
    State c;
    if (i > 0 && shared >= base) {
      c = path[std::min(shared, end)];
    } else {
      // A skip-list entry answers for its whole cell only (its walk may have ended above the
      // cell's level toward the cell's corner), so later queries reuse it inside that cell.
      c = start_state(u, v, stop);
      base = skip_level_ != 0 && stop >= skip_level_ ? skip_level_ : 0;
      path[c.level] = c;
    }
    while (c.kind == kDag && c.level < stop) {
      step(c, u, v);
      if (c.kind != kDone) path[c.level] = c;
    }
    end = c.level;
    const uint32_t index = c.kind == kTreelet ? treelet_find(c, u, v, stop) : c.last;
    if (index != cached_index) cached_index = index, cached_value = value_of(index);
    lit[i] = queries[i].threshold <= cached_value;
    pu = u;
    pv = v;
  }
}

SHADOWTILES_ISA_CLONES uint32_t DagMhTileView::pcf_lit_count(uint32_t u0, uint32_t v0, uint32_t kw, uint32_t kh,
                                                             float depth, float bias) const {
  assert(kw >= 1 && kh >= 1 && u0 < size_ && v0 < size_ && kw <= size_ - u0 && kh <= size_ - v0);
  if (size_ == 0 || u0 >= size_ || v0 >= size_) return 0;
  kw = std::min(kw, size_ - u0);
  kh = std::min(kh, size_ - v0);
  if (kw == 0 || kh == 0) return 0;
  const uint32_t u1 = u0 + kw - 1, v1 = v0 + kh - 1;
  const unsigned lca = levels_ - unsigned(std::bit_width((u0 ^ u1) | (v0 ^ v1)));
  if (skip_level_ != 0 && lca < skip_level_) {
    // Across skip list cells: each part from its own entry (codec/skip_cell_parts.hpp).
    return sum_over_skip_cell_parts(u0, v0, u1, v1, levels_ - skip_level_,
                                    [&](uint32_t pu0, uint32_t pv0, uint32_t pu1, uint32_t pv1)
                                        __attribute__((always_inline)) {
                                      const unsigned part_lca =
                                          levels_ - unsigned(std::bit_width((pu0 ^ pu1) | (pv0 ^ pv1)));
                                      State s = start_state(pu0, pv0, part_lca);
                                      while (s.kind == kDag && s.level < part_lca) step(s, pu0, pv0);
                                      return count_from_ancestor(s, pu0, pv0, pu1, pv1, depth, bias);
                                    });
  }
  State s = start_state(u0, v0, lca);
  while (s.kind == kDag && s.level < lca) step(s, u0, v0);
  return count_from_ancestor(s, u0, v0, u1, v1, depth, bias);
}

// Inlined into both PCF entry points, so it runs in their x86-64-v3 copies.
[[gnu::always_inline]] inline uint32_t DagMhTileView::count_from_ancestor(State s, uint32_t u0, uint32_t v0,
                                                                          uint32_t u1, uint32_t v1, float depth,
                                                                          float bias) const {
  // The walk ended at or above the common ancestor: one value decides the whole box.
  if (s.kind == kDone) return depth <= value_of(s.last) + bias ? (u1 - u0 + 1) * (v1 - v0 + 1) : 0;
  const unsigned L = levels_;
  // Last-node cache: path[l] is the previous sample's state at level l (lca <= l <= end); each sample
  // resumes from the deepest level it shares with the previous one.
  State path[F::kMaxLevels + 1];
  path[s.level] = s;
  unsigned end = s.level;
  uint32_t lit = 0, cached_index = UINT32_MAX, pu = u0, pv = v0;
  float cached_value = 0;
  // Two phases per group of samples: the walks give every sample's value index, then the values
  // are read. A value costs dependent misses (chunk-table entry, then chunk) that only its index
  // can start, so the group's entries are requested together, then its chunks, then the values
  // decoded: a 3x3 kernel's samples lie in up to 4 chunks, whose misses then overlap instead of
  // queuing. (Session 15 prefetched the chunks alone and the miss moved to the entries.)
  // Samples with the value index of the one before them join its run: on a shallow tree most of a
  // kernel is one run, read once and with no prefetch.
  constexpr unsigned kGroup = 32;
  uint32_t indices[kGroup], run_lengths[kGroup];
  unsigned count = 0;
  // A box inside one treelet: every sample's walk stays in it (no DAG step), so the treelet levels
  // down to the common ancestor are read once, not per sample.
  const unsigned lca = L - unsigned(std::bit_width((u0 ^ u1) | (v0 ^ v1)));
  const bool in_treelet = s.kind == kTreelet && s.level <= lca;  // (callers walk no deeper than lca)
  TreeletPrefix prefix;
  if (in_treelet) prefix = treelet_prefix(s, u0, v0, lca);
  // Inlined (as every helper here) so it runs in the caller's x86-64-v3 copy, not the baseline.
  auto flush = [&]() __attribute__((always_inline)) {
    if (count > 1) {
      for (unsigned i = 0; i < count; ++i) prefetch_chunk_entry(indices[i]);
      for (unsigned i = 0; i < count; ++i) prefetch_chunk(indices[i]);
    }
    for (unsigned i = 0; i < count; ++i) {
      if (indices[i] != cached_index) cached_index = indices[i], cached_value = value_of(indices[i]);
      if (depth <= cached_value + bias) lit += run_lengths[i];
    }
    count = 0;
  };
  auto add = [&](uint32_t index) __attribute__((always_inline)) {
    if (count > 0 && indices[count - 1] == index) {
      ++run_lengths[count - 1];
      return;
    }
    if (count == kGroup) flush();
    indices[count] = index, run_lengths[count++] = 1;
  };
  for (uint32_t v = v0; v <= v1; ++v)
    for (uint32_t u = u0; u <= u1; ++u) {
      const unsigned shared = L - unsigned(std::bit_width((u ^ pu) | (v ^ pv)));
      State c = path[std::min(shared, end)];
      while (c.kind == kDag && c.level < L) {
        step(c, u, v);
        if (c.kind != kDone) path[c.level] = c;
      }
      end = c.level;
      pu = u, pv = v;
      add(c.kind != kTreelet ? c.last
          : in_treelet       ? treelet_find_below(c, u, v, prefix)
                             : treelet_find(c, u, v, L));
    }
  flush();
  return lit;
}

SHADOWTILES_ISA_CLONES void DagMhTileView::pcf_count_sorted(std::span<const TexelQuery> corners, uint32_t k,
                                                            uint32_t* counts) const {
  for (const TexelQuery& c : corners)
    if (size_ == 0 || k == 0 || c.u >= size_ || c.v >= size_ || k > size_ - c.u || k > size_ - c.v) {
      // Out of contract (or a default-constructed view): answered as pcf_lit_count does, one by one.
      for (size_t i = 0; i < corners.size(); ++i)
        counts[i] = pcf_lit_count(corners[i].u, corners[i].v, k, k, corners[i].threshold, 0.0f);
      return;
    }
  const unsigned L = levels_;
  State path[F::kMaxLevels + 1];  // path[base..end]: the previous box's walk toward its corner
  unsigned base = 0, end = 0;
  uint32_t pu = 0, pv = 0;
  for (size_t i = 0; i < corners.size(); ++i) {
    const uint32_t u0 = corners[i].u, v0 = corners[i].v, u1 = u0 + k - 1, v1 = v0 + k - 1;
    const unsigned lca = L - unsigned(std::bit_width((u0 ^ u1) | (v0 ^ v1)));
    const unsigned shared = L - unsigned(std::bit_width((u0 ^ pu) | (v0 ^ pv)));
    State s;
    if (i > 0 && shared >= base && lca >= base) {
      // Nodes down to `shared` lie on both corners' paths; the walk toward this corner goes on there.
      s = path[std::min({shared, end, lca})];
    } else {
      // A skip-list entry answers for its cell only (as in lit_sorted).
      s = start_state(u0, v0, lca);
      base = skip_level_ != 0 && lca >= skip_level_ ? skip_level_ : 0;
      path[s.level] = s;
    }
    while (s.kind == kDag && s.level < lca) {
      step(s, u0, v0);
      if (s.kind != kDone) path[s.level] = s;
    }
    end = s.level;
    pu = u0;
    pv = v0;
    counts[i] = count_from_ancestor(s, u0, v0, u1, v1, corners[i].threshold, 0.0f);
  }
}

}  // namespace shadowtiles
