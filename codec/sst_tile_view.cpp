#include "codec/sst_tile_view.hpp"

#include <algorithm>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstring>
#include <string>

#include "codec/sst_format.hpp"
#include "common/byte_order.hpp"

namespace shadowtiles {
using namespace bytes;  // payload field loads (common/byte_order.hpp)
namespace {

namespace F = sst_format;

// A child offset of `width` bytes. Reads 4 bytes: validation guarantees the three offsets are
// followed by four child records of at least one byte each, so the over-read stays in the node.
inline uint32_t load_offset(const uint8_t* p, unsigned width) {
  return load_u32(p) & (width >= 4 ? ~uint32_t(0) : (uint32_t(1) << (8 * width)) - 1);
}

Error corrupt(const std::string& what) { return make_error(ErrorCode::corrupt_data, "SST payload: " + what); }

// Morton index -> (x, y): x takes the even bits.
uint32_t compact_even_bits(uint64_t m) {
  uint32_t r = 0;
  for (unsigned bit = 0; bit < 32; ++bit) r |= uint32_t((m >> (2 * bit)) & 1) << bit;
  return r;
}

// Walks one block's quadtree once, checking every record, and counts node kinds.
class BlockValidator {
 public:
  BlockValidator(const uint8_t* nodes, uint64_t node_bytes, SstStats& stats)
      : nodes_(nodes), end_(node_bytes), stats_(stats) {}

  // Returns the offset just past the block starting at `start`.
  Result<uint64_t> block(uint64_t start, uint32_t side) {
    if (start >= end_) return corrupt("block starts past the node section");
    width_ = nodes_[start];
    if (width_ < 1 || width_ > F::kMaxOffsetWidth) return corrupt("block offset width not in 1..4");
    ++stats_.block_width_bytes;
    return node(start + 1, side);
  }

 private:
  Result<uint64_t> node(uint64_t at, uint32_t side) {
    if (at >= end_) return corrupt("node record past the node section");
    const uint8_t tag = nodes_[at];
    const uint8_t kind = F::kind_of(tag);
    if (kind != F::kPlane && F::exponent_of(tag) != 0) return corrupt("tag bits set on a non-plane node");
    const uint64_t texels = uint64_t(side) * side;
    switch (kind) {
      case F::kOne:
        ++stats_.one_leaves, stats_.one_texels += texels;
        return at + 1;
      case F::kConstant:
        if (at + F::kConstantBytes > end_) return corrupt("constant record truncated");
        if (!std::isfinite(load_f32(nodes_ + at + 1))) return corrupt("non-finite constant");
        ++stats_.constant_leaves, stats_.constant_texels += texels;
        return at + F::kConstantBytes;
      case F::kPlane:
        if (at + F::kPlaneBytes > end_) return corrupt("plane record truncated");
        ++stats_.plane_leaves, stats_.plane_texels += texels;
        return at + F::kPlaneBytes;  // every bit pattern is a finite plane
      case F::kDense: {
        if (side < 2 || side > F::kMaxDenseSide) return corrupt("dense leaf at a side it is not allowed");
        const uint64_t bytes = F::dense_bytes(side);
        if (at + bytes > end_) return corrupt("dense record truncated");
        for (uint64_t i = 0; i < texels; ++i)
          if (!std::isfinite(load_f32(nodes_ + at + 1 + 4 * i))) return corrupt("non-finite dense value");
        ++stats_.dense_leaves, stats_.dense_texels += texels;
        stats_.dense_bytes += bytes;
        return at + bytes;
      }
      case F::kInternal: {
        if (side < 2) return corrupt("internal node below single texels");
        const uint64_t record_end = at + F::internal_bytes(width_);
        if (record_end > end_) return corrupt("internal record truncated");
        ++stats_.internal_nodes;
        stats_.internal_bytes += F::internal_bytes(width_);
        uint64_t child_start = record_end;
        for (unsigned child = 0; child < 4; ++child) {
          if (child > 0) {
            uint32_t offset = 0;
            std::memcpy(&offset, nodes_ + at + 1 + (child - 1) * width_, width_);
            if (record_end + offset != child_start) return corrupt("child offset does not match the layout");
          }
          auto child_end = node(child_start, side / 2);
          if (!child_end) return child_end.error();
          child_start = *child_end;
        }
        return child_start;
      }
      default:
        return corrupt("unknown node kind " + std::to_string(kind));
    }
  }

  const uint8_t* nodes_;
  uint64_t end_;
  SstStats& stats_;
  unsigned width_ = 1;
};

}  // namespace

Result<SstTileView> SstTileView::parse(std::span<const uint8_t> payload) {
  if (payload.size() < F::kHeaderBytes) return corrupt("shorter than its header");
  const uint8_t* p = payload.data();
  if (std::memcmp(p + F::kOffMagic, F::kMagic, 4) != 0) return corrupt("bad magic");
  const uint16_t version = load_u16(p + F::kOffVersion);
  if (version > F::kFormatVersion)
    return make_error(ErrorCode::unsupported, "SST payload format version " + std::to_string(version) +
                                                  " is newer than this reader (" +
                                                  std::to_string(F::kFormatVersion) + ")");
  if (version != F::kFormatVersion) return corrupt("unknown format version");
  if (load_u16(p + F::kOffFlags) != 0) return corrupt("unknown flags");
  SstTileView view;
  view.size_ = load_u32(p + F::kOffSize);
  view.block_side_ = load_u32(p + F::kOffBlockSide);
  view.blocks_per_side_ = load_u32(p + F::kOffBlocksPerSide);
  const uint32_t node_bytes = load_u32(p + F::kOffNodeBytes);
  if (view.size_ == 0 || !std::has_single_bit(view.size_) || view.size_ > F::kMaxSize)
    return corrupt("tile size not a power of two up to 2^20");
  if (view.block_side_ != std::min(F::kBlockSide, view.size_)) return corrupt("block side does not match the size");
  if (view.blocks_per_side_ != view.size_ / view.block_side_) return corrupt("block count does not match the size");
  const uint64_t blocks = uint64_t(view.blocks_per_side_) * view.blocks_per_side_;
  const uint64_t grid_bytes = blocks * 4;
  if (uint64_t(payload.size()) != F::kHeaderBytes + grid_bytes + node_bytes)
    return corrupt("size " + std::to_string(payload.size()) + " does not match its sections");
  view.levels_ = unsigned(std::countr_zero(view.size_));
  view.block_shift_ = unsigned(std::countr_zero(view.block_side_));
  view.grid_ = p + F::kHeaderBytes;
  view.nodes_ = view.grid_ + grid_bytes;

  SstStats& stats = view.stats_;
  stats.size = view.size_;
  stats.block_side = view.block_side_;
  stats.blocks = uint32_t(blocks);
  stats.payload_bytes = payload.size();
  stats.header_bytes = F::kHeaderBytes;
  stats.grid_bytes = grid_bytes;
  // Blocks must follow each other in Morton order and tile the node section exactly.
  BlockValidator validator(view.nodes_, node_bytes, stats);
  uint64_t expected = 0;
  for (uint64_t m = 0; m < blocks; ++m) {
    const uint32_t bx = compact_even_bits(m), by = compact_even_bits(m >> 1);
    const uint32_t offset = load_u32(view.grid_ + (uint64_t(by) * view.blocks_per_side_ + bx) * 4);
    if (offset != expected) return corrupt("block offsets do not follow the Morton layout");
    auto end = validator.block(offset, view.block_side_);
    if (!end) return end.error();
    expected = *end;
  }
  if (expected != node_bytes) return corrupt("bytes after the last block");
  return view;
}

const uint8_t* SstTileView::block_root(uint32_t bx, uint32_t by, unsigned& width) const {
  const uint8_t* block = nodes_ + load_u32(grid_ + (size_t(by) * blocks_per_side_ + bx) * 4);
  width = block[0];
  return block + 1;
}

float SstTileView::lookup(uint32_t u, uint32_t v, unsigned max_level) const {
  assert(u < size_ && v < size_);
  u &= size_ - 1;
  v &= size_ - 1;
  if (max_level < levels_) {
    const uint32_t cell = size_ >> max_level;
    u &= ~(cell - 1);
    v &= ~(cell - 1);
  }
  unsigned width;
  const uint8_t* node = block_root(u >> block_shift_, v >> block_shift_, width);
  uint32_t x = u & (block_side_ - 1), y = v & (block_side_ - 1), side = block_side_;
  for (;;) {
    const uint8_t tag = *node;
    switch (F::kind_of(tag)) {
      case F::kInternal: {
        side >>= 1;
        const unsigned child = unsigned(x >= side) | unsigned(y >= side) << 1;
        x &= side - 1;
        y &= side - 1;
        const uint8_t* record_end = node + F::internal_bytes(width);
        node = child == 0 ? record_end : record_end + load_offset(node + 1 + (child - 1) * width, width);
        break;
      }
      case F::kOne:
        return 1.0f;
      case F::kConstant:
        return load_f32(node + 1);
      case F::kPlane:
        return F::load_plane(node).value(x, y);
      default:  // kDense (validated)
        return load_f32(node + 1 + 4 * (size_t(y) * side + x));
    }
  }
}

uint32_t SstTileView::count_node(const uint8_t* node, unsigned width, uint32_t ox, uint32_t oy, uint32_t side,
                                 Box box, float threshold) const {
  const uint32_t area = (box.x1 - box.x0) * (box.y1 - box.y0);
  const uint8_t tag = *node;
  switch (F::kind_of(tag)) {
    case F::kInternal: {
      const uint32_t half = side >> 1;
      const uint8_t* record_end = node + F::internal_bytes(width);
      uint32_t lit = 0;
      for (unsigned child = 0; child < 4; ++child) {
        const uint32_t cx = ox + (child & 1) * half, cy = oy + (child >> 1) * half;
        const Box part{std::max(box.x0, cx), std::max(box.y0, cy), std::min(box.x1, cx + half),
                       std::min(box.y1, cy + half)};
        if (part.x0 >= part.x1 || part.y0 >= part.y1) continue;
        const uint8_t* child_node =
            child == 0 ? record_end : record_end + load_offset(node + 1 + (child - 1) * width, width);
        lit += count_node(child_node, width, cx, cy, half, part, threshold);
      }
      return lit;
    }
    case F::kOne:
      return threshold <= 1.0f ? area : 0;
    case F::kConstant:
      return threshold <= load_f32(node + 1) ? area : 0;
    case F::kPlane: {
      const F::PlaneBits plane = F::load_plane(node);
      const uint32_t x0 = box.x0 - ox, y0 = box.y0 - oy, x1 = box.x1 - 1 - ox, y1 = box.y1 - 1 - oy;
      const float corners[4] = {plane.value(x0, y0), plane.value(x1, y0), plane.value(x0, y1), plane.value(x1, y1)};
      if (threshold <= *std::min_element(corners, corners + 4)) return area;
      if (threshold > *std::max_element(corners, corners + 4)) return 0;
      uint32_t lit = 0;
      for (uint32_t y = y0; y <= y1; ++y)
        for (uint32_t x = x0; x <= x1; ++x) lit += threshold <= plane.value(x, y);
      return lit;
    }
    default: {  // kDense (validated)
      uint32_t lit = 0;
      for (uint32_t y = box.y0 - oy; y < box.y1 - oy; ++y)
        for (uint32_t x = box.x0 - ox; x < box.x1 - ox; ++x)
          lit += threshold <= load_f32(node + 1 + 4 * (size_t(y) * side + x));
      return lit;
    }
  }
}

uint32_t SstTileView::lit_count(uint32_t u0, uint32_t v0, uint32_t kw, uint32_t kh, float threshold) const {
  assert(u0 < size_ && v0 < size_ && kw <= size_ - u0 && kh <= size_ - v0);
  u0 = std::min(u0, size_);
  v0 = std::min(v0, size_);
  const Box box{u0, v0, u0 + std::min(kw, size_ - u0), v0 + std::min(kh, size_ - v0)};
  if (box.x0 >= box.x1 || box.y0 >= box.y1) return 0;
  uint32_t lit = 0;
  for (uint32_t by = box.y0 >> block_shift_; by <= (box.y1 - 1) >> block_shift_; ++by)
    for (uint32_t bx = box.x0 >> block_shift_; bx <= (box.x1 - 1) >> block_shift_; ++bx) {
      const uint32_t ox = bx << block_shift_, oy = by << block_shift_;
      const Box part{std::max(box.x0, ox), std::max(box.y0, oy), std::min(box.x1, ox + block_side_),
                     std::min(box.y1, oy + block_side_)};
      unsigned width;
      const uint8_t* root = block_root(bx, by, width);
      lit += count_node(root, width, ox, oy, block_side_, part, threshold);
    }
  return lit;
}

}  // namespace shadowtiles
