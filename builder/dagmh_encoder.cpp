#include "builder/dagmh_encoder.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <string>
#include <unordered_map>

#include "codec/dagmh_format.hpp"
#include "codec/mh_format.hpp"
#include "common/isa_clones.hpp"

namespace shadowtiles {
namespace {

namespace F = dagmh_format;
namespace MF = mh_format;

Error invalid(const std::string& m) { return make_error(ErrorCode::invalid_input, "DAG-MH encoder: " + m); }

uint64_t mix64(uint64_t x) {
  x ^= x >> 33;
  x *= 0xff51afd7ed558ccdULL;
  x ^= x >> 33;
  x *= 0xc4ceb9fe1a85ec53ULL;
  return x ^ (x >> 33);
}

// Shape of a DAG node: own-value flag, child codes, canonical child ids. Equal keys = equal subtree
// shapes (children are canonical already), so the map's full key comparison is the structural test.
using NodeKey = std::array<uint32_t, 5>;
struct NodeKeyHash {
  uint64_t mask;
  size_t operator()(const NodeKey& k) const {
    uint64_t h = 0x9e3779b97f4a7c15ULL;
    for (uint32_t x : k) h = mix64(h ^ x);
    return size_t(h & mask);
  }
};
struct BytesHash {
  uint64_t mask;
  size_t operator()(const std::string& s) const {
    uint64_t h = 0x9e3779b97f4a7c15ULL;
    for (unsigned char c : s) h = mix64(h ^ c);
    return size_t(h & mask);
  }
};

struct DagNode {
  uint8_t mask = 0;
  bool valued = false;
  uint32_t child_id[4] = {0, 0, 0, 0};
  uint64_t before[4] = {0, 0, 0, 0};  // values in the children before child i
  uint64_t total = 0;                 // values in the subtree (own included)
};

struct Ref {
  unsigned code;
  uint32_t id;
  uint64_t values;
};

unsigned width_for(uint64_t max_value) {
  unsigned w = 1;
  while (w < 4 && max_value >= (uint64_t(1) << (8 * w))) ++w;
  return w;
}

void put_uint(std::vector<uint8_t>& out, uint64_t x, unsigned width) {
  for (unsigned i = 0; i < width; ++i) out.push_back(uint8_t(x >> (8 * i)));
}
void put_f32(std::vector<uint8_t>& out, float f) {
  uint8_t b[4];
  std::memcpy(b, &f, 4);
  out.insert(out.end(), b, b + 4);
}

class Encoder {
 public:
  Encoder(const MhHierarchy& h, const DagMhOptions& o)
      : h_(h),
        H_(o.treelet_height),
        tb_(F::treelet_bytes(o.treelet_height)),
        nodes_map_(16, NodeKeyHash{o.hash_bits >= 64 ? ~0ULL : ((1ULL << o.hash_bits) - 1)}),
        treelet_map_(16, BytesHash{o.hash_bits >= 64 ? ~0ULL : ((1ULL << o.hash_bits) - 1)}),
        block_height_(h.block_count(), -1) {}

  Ref emit_root() {
    return emit(true, h_.root, h_.root_mask != 0 ? int64_t(h_.root_block) : -1);
  }

  const MhHierarchy& h_;
  unsigned H_;
  size_t tb_;
  std::unordered_map<NodeKey, uint32_t, NodeKeyHash> nodes_map_;
  std::unordered_map<std::string, uint32_t, BytesHash> treelet_map_;
  std::vector<DagNode> nodes_;
  std::vector<std::string> treelets_;
  std::vector<DepthInterval> values_;  // depth-first value list (intervals; values chosen later)
  std::vector<int> block_height_;

 private:
  // Levels of nodes below the owner of block b.
  int block_height(uint32_t b) {
    if (block_height_[b] >= 0) return block_height_[b];
    const uint8_t mask = h_.block_mask[b];
    int hb = 1;
    unsigned r = 0;
    for (unsigned i = 0; i < 4; ++i)
      if (MF::child_code(mask, i) & 2u) hb = std::max(hb, 1 + block_height(h_.child_block[h_.block_first_child[b] + r++]));
    return block_height_[b] = hb;
  }

  template <class Fn>
  void for_children(uint32_t b, Fn&& fn) {
    const uint8_t mask = h_.block_mask[b];
    unsigned r = 0, vr = 0;
    for (unsigned i = 0; i < 4; ++i) {
      const unsigned code = MF::child_code(mask, i);
      if (code == 0) continue;
      const bool valued = code & 1u;
      const DepthInterval iv = valued ? h_.intervals[h_.block_first_value[b] + vr++] : DepthInterval{};
      const int64_t child = (code & 2u) ? int64_t(h_.child_block[h_.block_first_child[b] + r++]) : -1;
      fn(i, valued, iv, child);
    }
  }

  // Depth-first fill of a treelet bitmap (same order as the value list).
  void fill(std::string& bits, bool valued, const DepthInterval& iv, int64_t block, uint32_t index, unsigned depth) {
    if (valued) {
      bits[index / 8] = char(uint8_t(bits[index / 8]) | (1u << (index % 8)));
      values_.push_back(iv);
    }
    if (block < 0) return;
    for_children(uint32_t(block), [&](unsigned i, bool cv, const DepthInterval& civ, int64_t cb) {
      fill(bits, cv, civ, cb, index + 1 + i * F::complete_nodes(H_ - 1 - depth), depth + 1);
    });
  }

  Ref emit(bool valued, const DepthInterval& iv, int64_t block) {
    if (block < 0) {
      values_.push_back(iv);
      return {F::kCodeLeaf, 0, 1};
    }
    const size_t start = values_.size();
    if (unsigned(1 + block_height(uint32_t(block))) <= H_) {
      std::string bits(tb_, '\0');
      fill(bits, valued, iv, block, 0, 0);
      auto [it, fresh] = treelet_map_.try_emplace(bits, uint32_t(treelets_.size()));
      if (fresh) treelets_.push_back(bits);
      return {F::kCodeTreelet, it->second, values_.size() - start};
    }
    if (valued) values_.push_back(iv);
    DagNode node;
    node.valued = valued;
    uint64_t in_children = 0;
    for_children(uint32_t(block), [&](unsigned i, bool cv, const DepthInterval& civ, int64_t cb) {
      Ref r = emit(cv, civ, cb);
      node.mask = uint8_t(node.mask | (r.code << (2 * i)));
      node.child_id[i] = r.id;
      node.before[i] = in_children;
      in_children += r.values;
    });
    node.total = in_children + (valued ? 1 : 0);
    NodeKey key{uint32_t(node.mask) | (uint32_t(valued) << 8), node.child_id[0], node.child_id[1], node.child_id[2],
                node.child_id[3]};
    auto [it, fresh] = nodes_map_.try_emplace(key, uint32_t(nodes_.size()));
    if (fresh) nodes_.push_back(node);
    return {F::kCodeDag, it->second, node.total};
  }
};

// ---- value chunks ----

bool contains(const DepthInterval& iv, float x) { return std::isfinite(x) && x >= iv.lower && x <= iv.upper; }

struct BitWriter {
  std::vector<uint8_t>& out;
  uint64_t acc = 0;
  unsigned n = 0;
  void put(uint32_t x, unsigned bits) {
    acc |= uint64_t(x) << n;
    n += bits;
    while (n >= 8) {
      out.push_back(uint8_t(acc));
      acc >>= 8;
      n -= 8;
    }
  }
  void flush() {
    if (n > 0) out.push_back(uint8_t(acc));
    acc = 0;
    n = 0;
  }
};

// The largest lower and the smallest upper bound of the intervals: the grid's ends, the same for
// every b (computed once per chunk: try_grid runs for up to 24 values of b, and recomputing them
// was 12 % of a full-depth build's CPU, fzk_haus 16384² `anywhere`).
struct GridEnds {
  float lo_max = -std::numeric_limits<float>::infinity(), hi_min = std::numeric_limits<float>::infinity();
};
GridEnds grid_ends(const std::vector<DepthInterval>& d) {
  // Plain locals, not the struct's fields through std::max's references: those were kept in memory,
  // a store-to-load chain per interval (a tenth of the value coder's time on a full-depth tree).
  float lo_max = -std::numeric_limits<float>::infinity(), hi_min = std::numeric_limits<float>::infinity();
  for (const auto& iv : d) {
    lo_max = iv.lower > lo_max ? iv.lower : lo_max;
    hi_min = iv.upper < hi_min ? iv.upper : hi_min;
  }
  return {lo_max, hi_min};
}

// The grid of b bits over `ends`: c_l at the smallest upper bound, c_f the step that reaches the
// largest lower bound in 2^b - 1 steps.
void grid_for(const GridEnds& ends, unsigned b, float* c_l, float* c_f) {
  const float cl = std::isfinite(ends.hi_min) ? ends.hi_min : ends.lo_max;
  const uint32_t max_m = (uint32_t(1) << b) - 1;
  *c_l = cl;
  *c_f = ends.lo_max > cl ? float((double(ends.lo_max) - double(cl)) / double(max_m)) : 0.0f;
}

// Tries a b-bit grid over the differing intervals: c_l at the smallest upper bound (intervals below
// it contain it: m = 0), step so 2^b - 1 steps reach the largest lower bound. Every multiplier is
// checked with the decoder's expression; false when some interval has no grid point.
// Compiled for x86-64-v3 too: there std::fma is one instruction, in the baseline a libm call per
// multiplier checked (both round exactly once, so the grids found are the same).
SHADOWTILES_ISA_CLONES bool try_grid(const std::vector<DepthInterval>& d, const GridEnds& ends, unsigned b,
                                     float* c_l, float* c_f, std::vector<uint32_t>* ms) {
  const uint32_t max_m = (uint32_t(1) << b) - 1;
  float cl, cf;
  grid_for(ends, b, &cl, &cf);
  if (!std::isfinite(cl) || !std::isfinite(cf)) return false;
  if (!std::isfinite(F::dequantize(cl, cf, max_m))) return false;
  ms->clear();
  for (const auto& iv : d) {
    uint32_t m0 = 0;
    if (cf > 0 && iv.lower > cl) m0 = uint32_t(std::clamp(std::ceil((double(iv.lower) - cl) / cf), 0.0, double(max_m)));
    bool found = false;
    for (int64_t m : {int64_t(m0), int64_t(m0) + 1, int64_t(m0) - 1, int64_t(m0) + 2}) {
      if (m < 0 || m > int64_t(max_m)) continue;
      if (contains(iv, F::dequantize(cl, cf, uint32_t(m)))) {
        ms->push_back(uint32_t(m));
        found = true;
        break;
      }
    }
    if (!found) return false;
  }
  *c_l = cl;
  *c_f = cf;
  return true;
}

// The chunk's representative: the index of the lower bound contained in the most intervals (ties:
// the first). Every pair is tested (n <= kMaxChunkSize): the bounds are copied apart first so the
// inner loop runs over two plain float arrays without a branch, which the compiler vectorises (in
// the x86-64-v3 copy 8 intervals an instruction). It was a third of the chunk coder's time on a
// full-depth tree (fzk_haus 16384² `anywhere`, perf); DAG-MH encode 7.6-8.2 -> 7.4-7.5 thread-s.
SHADOWTILES_ISA_CLONES unsigned representative_index(const DepthInterval* iv, unsigned n) {
  float lower[F::kMaxChunkSize], upper[F::kMaxChunkSize];
  for (unsigned j = 0; j < n; ++j) lower[j] = iv[j].lower, upper[j] = iv[j].upper;
  unsigned best = 0, best_count = 0;
  for (unsigned i = 0; i < n; ++i) {
    const float x = lower[i];
    unsigned c = 0;  // DepthInterval::contains(x)
    for (unsigned j = 0; j < n; ++j) c += unsigned(x >= lower[j]) & unsigned(x <= upper[j]);
    if (c > best_count) best = i, best_count = c;
  }
  return best;
}

Status encode_chunk(const DepthInterval* iv, unsigned n, std::vector<uint8_t>& out) {
  const float rep = iv[representative_index(iv, n)].lower;
  if (!std::isfinite(rep)) return invalid("non-finite interval bound");
  put_f32(out, rep);
  std::vector<uint8_t> bitmap(F::bitmap_bytes(n), 0);
  std::vector<DepthInterval> diff;
  for (unsigned i = 0; i < n; ++i)
    if (!iv[i].contains(rep)) {
      bitmap[i / 8] = uint8_t(bitmap[i / 8] | (1u << (i % 8)));
      diff.push_back(iv[i]);
    }
  if (diff.empty()) {
    out.push_back(0);
    return Status::success();
  }
  const size_t k = diff.size();
  // Smallest b whose grid fits, if cheaper than raw floats.
  std::vector<uint32_t> ms;
  float cl = 0, cf = 0;
  unsigned b = F::kRawBits;
  const GridEnds ends = grid_ends(diff);
  for (unsigned bits = 1; bits <= F::kMaxQuantBits; ++bits) {
    if (8 + (k * bits + 7) / 8 >= 4 * k) break;
    if (try_grid(diff, ends, bits, &cl, &cf, &ms)) {
      b = bits;
      break;
    }
  }
  out.push_back(uint8_t(b));
  out.insert(out.end(), bitmap.begin(), bitmap.end());
  if (b == F::kRawBits) {
    for (const auto& d : diff) {
      const float x = mh_value_for(d);
      if (!contains(d, x)) return invalid("interval with no finite value");
      put_f32(out, x);
    }
    return Status::success();
  }
  put_f32(out, cl);
  put_f32(out, cf);
  BitWriter w{out};
  for (uint32_t m : ms) w.put(m, b);
  w.flush();
  return Status::success();
}


// The treelet-height-dependent part of a payload: DAG nodes and treelets, and the depth-first
// value intervals (the same list for every treelet height: pre-order of the same tree).
struct TopologyPart {
  std::vector<uint8_t> body;  // DAG section, then treelets
  uint64_t dag_bytes = 0, treelets = 0;
  unsigned ref_width = 1, count_width = 1;
  unsigned root_code = 0;
  uint32_t root_ref = 0;
  std::vector<DepthInterval> values;
};

// The chunk-size-dependent part: chunk offsets and chunk data.
struct ValuePart {
  std::vector<uint64_t> offsets;
  std::vector<uint8_t> chunks;
  unsigned offset_width = 1;
};

Status check_options(const DagMhOptions& o) {
  if (o.treelet_height < F::kMinTreeletHeight || o.treelet_height > F::kMaxTreeletHeight)
    return invalid("treelet height must be 2..5");
  if (o.chunk_size < 1 || o.chunk_size > F::kMaxChunkSize) return invalid("chunk size must be 1..1024");
  if (o.hash_bits < 1 || o.hash_bits > 64) return invalid("hash bits must be 1..64");
  return Status::success();
}

Result<TopologyPart> encode_topology(const MhHierarchy& h, const DagMhOptions& o) {
  Encoder e(h, o);
  const Ref root = e.emit_root();
  TopologyPart t;
  const uint64_t n_values = e.values_.size();
  if (n_values > UINT32_MAX) return invalid("too many values");

  // DAG layout: nodes were created children first; reversed, every reference points forward and
  // the root (created last) sits at offset 0.
  const unsigned wc = width_for(n_values);
  unsigned wr = 1;
  uint64_t dag_bytes = 0;
  for (;; ++wr) {
    dag_bytes = 0;
    for (const auto& n : e.nodes_) dag_bytes += F::node_bytes(n.mask, wr, wc);
    const uint64_t max_ref = std::max<uint64_t>(dag_bytes, e.treelets_.size());
    if (max_ref < (uint64_t(1) << (8 * wr)) || wr == 4) break;
  }
  if (dag_bytes > UINT32_MAX) return invalid("DAG over 4 GiB");
  std::vector<uint32_t> offset(e.nodes_.size());
  {
    uint64_t at = 0;
    for (size_t i = e.nodes_.size(); i-- > 0;) {
      offset[i] = uint32_t(at);
      at += F::node_bytes(e.nodes_[i].mask, wr, wc);
    }
  }
  std::vector<uint8_t>& body = t.body;
  for (size_t i = e.nodes_.size(); i-- > 0;) {
    const DagNode& n = e.nodes_[i];
    body.push_back(n.mask);
    body.push_back(n.valued ? 1 : 0);
    for (unsigned c = 0; c < 4; ++c) {
      const unsigned code = F::child_code(n.mask, c);
      if (code == F::kCodeTreelet) put_uint(body, n.child_id[c], wr);
      if (code == F::kCodeDag) put_uint(body, offset[n.child_id[c]], wr);
    }
    bool first = true;
    for (unsigned c = 0; c < 4; ++c) {
      if (F::child_code(n.mask, c) == 0) continue;
      if (!first) put_uint(body, n.before[c], wc);
      first = false;
    }
  }
  for (const auto& tl : e.treelets_) body.insert(body.end(), tl.begin(), tl.end());
  t.dag_bytes = dag_bytes;
  t.treelets = e.treelets_.size();
  t.ref_width = wr;
  t.count_width = wc;
  t.root_code = root.code;
  t.root_ref = root.code == F::kCodeDag ? offset[root.id] : root.code == F::kCodeTreelet ? root.id : 0;
  t.values = std::move(e.values_);
  return t;
}

Result<ValuePart> encode_values(const std::vector<DepthInterval>& values, unsigned chunk_size) {
  ValuePart v;
  for (uint64_t at = 0; at < values.size(); at += chunk_size) {
    v.offsets.push_back(v.chunks.size());
    const unsigned n = unsigned(std::min<uint64_t>(chunk_size, values.size() - at));
    if (Status s = encode_chunk(values.data() + at, n, v.chunks); !s) return s.error();
  }
  if (v.chunks.size() > UINT32_MAX) return invalid("values over 4 GiB");
  v.offset_width = width_for(v.chunks.size());
  return v;
}

std::vector<uint8_t> assemble(const MhHierarchy& h, unsigned treelet_height, unsigned chunk_size,
                              const TopologyPart& t, const ValuePart& v) {
  const unsigned wo = v.offset_width;
  std::vector<uint8_t> out;
  out.reserve(F::kHeaderBytes + t.body.size() + v.offsets.size() * wo + v.chunks.size());
  for (uint8_t b : F::kMagic) out.push_back(b);  // not insert(): GCC 12 -Wstringop-overflow false positive
  put_uint(out, F::kFormatVersion, 2);
  put_uint(out, 0, 2);
  put_uint(out, h.size, 4);
  out.push_back(uint8_t(h.levels));
  out.push_back(uint8_t(treelet_height));
  out.push_back(uint8_t(t.ref_width));
  out.push_back(uint8_t(t.count_width));
  out.push_back(uint8_t(wo));
  out.push_back(uint8_t(t.root_code));
  put_uint(out, chunk_size, 2);
  put_uint(out, t.root_ref, 4);
  put_uint(out, t.dag_bytes, 4);
  put_uint(out, t.treelets, 4);
  put_uint(out, t.values.size(), 4);
  put_uint(out, v.chunks.size(), 4);
  out.insert(out.end(), t.body.begin(), t.body.end());
  for (uint64_t off : v.offsets) put_uint(out, off, wo);
  out.insert(out.end(), v.chunks.begin(), v.chunks.end());
  return out;
}

}  // namespace

Result<std::vector<uint8_t>> encode_dagmh(const MhHierarchy& h, const DagMhOptions& o) {
  if (Status s = check_structure(h); !s) return s.error();
  if (Status s = check_options(o); !s) return s.error();
  auto topology = encode_topology(h, o);
  if (!topology) return topology.error();
  auto values = encode_values(topology->values, o.chunk_size);
  if (!values) return values.error();
  return assemble(h, o.treelet_height, o.chunk_size, *topology, *values);
}

Result<DagMhTopology> dagmh_topology(const MhHierarchy& h, unsigned treelet_height) {
  if (Status s = check_structure(h); !s) return s.error();
  const DagMhOptions o{treelet_height, 32, 64};
  if (Status s = check_options(o); !s) return s.error();
  Encoder e(h, o);
  const Ref root = e.emit_root();
  DagMhTopology t;
  t.nodes.reserve(e.nodes_.size());
  for (const DagNode& n : e.nodes_) {
    DagMhTopology::Node node;
    node.mask = n.mask;
    node.valued = n.valued;
    std::copy(std::begin(n.child_id), std::end(n.child_id), node.child_id);
    t.nodes.push_back(node);
  }
  t.treelets = std::move(e.treelets_);
  t.root_code = root.code;
  t.root_id = root.id;
  t.values = e.values_.size();
  return t;
}

Status for_each_dagmh_parameter(const MhHierarchy& h, const std::vector<unsigned>& heights,
                                const std::vector<unsigned>& chunks,
                                const std::function<Status(unsigned, unsigned, std::span<const uint8_t>)>& visit) {
  if (Status s = check_structure(h); !s) return s.error();
  for (unsigned height : heights)
    for (unsigned c : chunks)
      if (Status s = check_options(DagMhOptions{height, c, 64}); !s) return s.error();
  // Every treelet height lists the same values (pre-order of one tree): chunks are coded once per size.
  std::vector<ValuePart> value_parts;
  for (size_t hi = 0; hi < heights.size(); ++hi) {
    auto topology = encode_topology(h, DagMhOptions{heights[hi], 32, 64});
    if (!topology) return topology.error();
    for (size_t ci = 0; ci < chunks.size(); ++ci) {
      if (hi == 0) {
        auto values = encode_values(topology->values, chunks[ci]);
        if (!values) return values.error();
        value_parts.push_back(std::move(*values));
      }
      const std::vector<uint8_t> payload = assemble(h, heights[hi], chunks[ci], *topology, value_parts[ci]);
      if (Status s = visit(heights[hi], chunks[ci], payload); !s) return s;
    }
  }
  return Status::success();
}

Result<std::vector<DagMhStudyPoint>> dagmh_parameter_study(const MhHierarchy& hierarchy,
                                                           const std::vector<unsigned>& heights,
                                                           const std::vector<unsigned>& chunks) {
  std::vector<DagMhStudyPoint> points;
  Status s = for_each_dagmh_parameter(hierarchy, heights, chunks,
                                      [&](unsigned height, unsigned c, std::span<const uint8_t> payload) {
                                        points.push_back({height, c, payload.size()});
                                        return Status::success();
                                      });
  if (!s) return s.error();
  return points;
}

}  // namespace shadowtiles
