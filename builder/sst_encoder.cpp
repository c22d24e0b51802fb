#include "builder/sst_encoder.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "builder/sst_plane_fit.hpp"
#include "codec/sst_format.hpp"

namespace shadowtiles {
namespace {

namespace F = sst_format;
static_assert(std::endian::native == std::endian::little, "SST payloads are written with memcpy: little-endian only");

// Offset width assumed while choosing between a dense leaf and subdivision (the real width is
// only known once the block is built; the choice is a size heuristic, never a correctness one).
constexpr unsigned kEstimatedOffsetWidth = 2;

struct QuadNode {
  F::Kind kind = F::kOne;
  uint32_t side = 0;
  float constant = 0;
  F::PlaneBits plane;
  uint32_t dense_first = 0;      // index into BlockBuilder::dense_ (kDense)
  uint32_t children[4] = {0, 0, 0, 0};  // node indices (kInternal), Morton order
};

// One block's quadtree, built top-down, then serialised depth-first with the narrowest offsets.
class BlockBuilder {
 public:
  explicit BlockBuilder(const TileIntervals& t) : t_(t) {}

  void build(uint32_t x0, uint32_t y0, uint32_t side) {
    nodes_.clear();
    dense_.clear();
    build_node(x0, y0, side);
  }

  void serialise(std::vector<uint8_t>& out) const {
    unsigned width = 1;
    while (width < F::kMaxOffsetWidth && max_child_offset(0, width).second >= (uint64_t(1) << (8 * width))) ++width;
    out.push_back(uint8_t(width));
    write_node(0, width, out);
  }

 private:
  // Returns the node's index and its estimated record size in bytes.
  std::pair<uint32_t, uint64_t> build_node(uint32_t x0, uint32_t y0, uint32_t side) {
    const uint32_t index = uint32_t(nodes_.size());
    nodes_.emplace_back();
    nodes_[index].side = side;
    float max_lower = -std::numeric_limits<float>::infinity(), min_upper = std::numeric_limits<float>::infinity();
    for (uint32_t j = 0; j < side; ++j)
      for (uint32_t i = 0; i < side; ++i) {
        const DepthInterval& d = t_.at(x0 + i, y0 + j);
        max_lower = std::max(max_lower, d.lower);
        min_upper = std::min(min_upper, d.upper);
      }
    if (max_lower <= 1.0f && 1.0f <= min_upper) return {index, 1};
    if (max_lower <= min_upper) {  // max_lower is some texel's lower: inside every interval of the node
      nodes_[index].kind = F::kConstant;
      nodes_[index].constant = max_lower;
      return {index, F::kConstantBytes};
    }
    if (auto plane = fit_sst_plane(t_, x0, y0, side)) {
      nodes_[index].kind = F::kPlane;
      nodes_[index].plane = *plane;
      return {index, F::kPlaneBytes};
    }
    // side > 1 here: a single texel's interval always holds its own lower bound.
    const uint32_t half = side / 2;
    uint64_t subdivided = F::internal_bytes(kEstimatedOffsetWidth);
    uint32_t children[4];
    const size_t dense_mark = dense_.size();
    for (uint32_t child = 0; child < 4; ++child) {
      auto [child_index, bytes] = build_node(x0 + (child & 1) * half, y0 + (child >> 1) * half, half);
      children[child] = child_index;
      subdivided += bytes;
    }
    if (side <= F::kMaxDenseSide && F::dense_bytes(side) <= subdivided) {
      nodes_.resize(index + 1);  // the children were the last nodes added; drop them
      dense_.resize(dense_mark);
      QuadNode& node = nodes_[index];
      node.kind = F::kDense;
      node.dense_first = uint32_t(dense_.size());
      for (uint32_t j = 0; j < side; ++j)
        for (uint32_t i = 0; i < side; ++i) dense_.push_back(t_.at(x0 + i, y0 + j).lower);
      return {index, F::dense_bytes(side)};
    }
    QuadNode& node = nodes_[index];
    node.kind = F::kInternal;
    std::copy(children, children + 4, node.children);
    return {index, subdivided};
  }

  uint64_t record_bytes(const QuadNode& node, unsigned width) const {
    switch (node.kind) {
      case F::kInternal: return F::internal_bytes(width);
      case F::kOne: return 1;
      case F::kConstant: return F::kConstantBytes;
      case F::kPlane: return F::kPlaneBytes;
      case F::kDense: return F::dense_bytes(node.side);
    }
    return 0;
  }

  // Subtree bytes of `index` at offset width `width`, and the largest child offset inside it.
  std::pair<uint64_t, uint64_t> max_child_offset(uint32_t index, unsigned width) const {
    const QuadNode& node = nodes_[index];
    uint64_t bytes = record_bytes(node, width);
    if (node.kind != F::kInternal) return {bytes, 0};
    uint64_t largest = 0, offset = 0;
    for (uint32_t child = 0; child < 4; ++child) {
      if (child > 0) largest = std::max(largest, offset);  // offsets of children 1..3
      auto [child_bytes, child_largest] = max_child_offset(node.children[child], width);
      largest = std::max(largest, child_largest);
      offset += child_bytes;
    }
    return {bytes + offset, largest};
  }

  uint64_t subtree_bytes(uint32_t index, unsigned width) const { return max_child_offset(index, width).first; }

  void write_node(uint32_t index, unsigned width, std::vector<uint8_t>& out) const {
    const QuadNode& node = nodes_[index];
    switch (node.kind) {
      case F::kOne:
        out.push_back(F::make_tag(F::kOne));
        return;
      case F::kConstant:
        out.push_back(F::make_tag(F::kConstant));
        append(out, &node.constant, 4);
        return;
      case F::kPlane: {
        out.push_back(F::make_tag(F::kPlane, node.plane.E));
        const uint32_t a = node.plane.A;
        const uint8_t a_bytes[3] = {uint8_t(a), uint8_t(a >> 8), uint8_t(a >> 16)};
        append(out, a_bytes, 3);
        append(out, &node.plane.B, 2);
        append(out, &node.plane.C, 2);
        return;
      }
      case F::kDense:
        out.push_back(F::make_tag(F::kDense));
        append(out, dense_.data() + node.dense_first, size_t(node.side) * node.side * 4);
        return;
      case F::kInternal: {
        out.push_back(F::make_tag(F::kInternal));
        uint64_t offset = 0;
        for (uint32_t child = 0; child < 3; ++child) {
          offset += subtree_bytes(node.children[child], width);
          const uint32_t o = uint32_t(offset);
          append(out, &o, width);  // little-endian: the low `width` bytes
        }
        for (uint32_t child = 0; child < 4; ++child) write_node(node.children[child], width, out);
        return;
      }
    }
  }

  static void append(std::vector<uint8_t>& out, const void* bytes, size_t n) {
    const auto* p = static_cast<const uint8_t*>(bytes);
    out.insert(out.end(), p, p + n);
  }

  const TileIntervals& t_;
  std::vector<QuadNode> nodes_;
  std::vector<float> dense_;
};

Status check_intervals(const TileIntervals& t) {
  if (t.size == 0 || !std::has_single_bit(t.size) || t.size > F::kMaxSize)
    return make_error(ErrorCode::invalid_input, "SST: tile size must be a power of two up to 2^20");
  if (t.texels.size() != size_t(t.size) * t.size)
    return make_error(ErrorCode::invalid_input, "SST: texel count does not match the tile size");
  for (const DepthInterval& d : t.texels)
    if (!std::isfinite(d.lower) || std::isnan(d.upper) || d.lower > d.upper)
      return make_error(ErrorCode::invalid_input, "SST: texel interval is not a finite lower <= upper");
  return {};
}

void put_u16(std::vector<uint8_t>& out, size_t at, uint16_t x) { std::memcpy(out.data() + at, &x, 2); }
void put_u32(std::vector<uint8_t>& out, size_t at, uint32_t x) { std::memcpy(out.data() + at, &x, 4); }

// Morton index -> (x, y): x takes the even bits.
uint32_t compact_even_bits(uint64_t m) {
  uint32_t r = 0;
  for (unsigned bit = 0; bit < 32; ++bit) r |= uint32_t((m >> (2 * bit)) & 1) << bit;
  return r;
}

}  // namespace

bool sst_encoder_available() { return true; }

Result<std::vector<uint8_t>> encode_sst_tile(const TileIntervals& intervals) {
  if (Status s = check_intervals(intervals); !s) return s.error();
  const uint32_t block_side = std::min(F::kBlockSide, intervals.size);
  const uint32_t blocks_per_side = intervals.size / block_side;
  const size_t grid_bytes = size_t(blocks_per_side) * blocks_per_side * 4;
  std::vector<uint8_t> out(F::kHeaderBytes + grid_bytes, 0);
  std::memcpy(out.data() + F::kOffMagic, F::kMagic, 4);
  put_u16(out, F::kOffVersion, F::kFormatVersion);
  put_u16(out, F::kOffFlags, 0);
  put_u32(out, F::kOffSize, intervals.size);
  put_u32(out, F::kOffBlockSide, block_side);
  put_u32(out, F::kOffBlocksPerSide, blocks_per_side);
  const size_t nodes_start = out.size();
  BlockBuilder builder(intervals);
  const uint64_t blocks = uint64_t(blocks_per_side) * blocks_per_side;
  for (uint64_t m = 0; m < blocks; ++m) {
    const uint32_t bx = compact_even_bits(m), by = compact_even_bits(m >> 1);
    const uint64_t offset = out.size() - nodes_start;
    if (offset > std::numeric_limits<uint32_t>::max())
      return make_error(ErrorCode::invalid_input, "SST: tile payload exceeds 32-bit offsets");
    put_u32(out, F::kHeaderBytes + (size_t(by) * blocks_per_side + bx) * 4, uint32_t(offset));
    builder.build(bx * block_side, by * block_side, block_side);
    builder.serialise(out);
  }
  const uint64_t node_bytes = out.size() - nodes_start;
  if (node_bytes > std::numeric_limits<uint32_t>::max())
    return make_error(ErrorCode::invalid_input, "SST: tile payload exceeds 32-bit offsets");
  put_u32(out, F::kOffNodeBytes, uint32_t(node_bytes));
  return out;
}

}  // namespace shadowtiles
