#include "codec/cpvs_tile_view.hpp"

#include <algorithm>
#include <bit>
#include <cstring>
#include <string>

namespace shadowtiles {
namespace {

Error corrupt(const std::string& what) { return make_error(ErrorCode::corrupt_data, "cpvs payload: " + what); }

// Bits of a leaf's 8x8 (or 4x4, `row_bits` = 4) slice covered by the half-open texel box.
uint64_t box_mask(unsigned row_bits, uint32_t x0, uint32_t x1, uint32_t y0, uint32_t y1) {
  uint64_t row = ((uint64_t(1) << (x1 - x0)) - 1) << x0;
  uint64_t mask = 0;
  for (uint32_t y = y0; y < y1; ++y) mask |= row << (row_bits * y);
  return mask;
}

// Octree child of voxel (u, v, step) in a node whose children have side `half` (format: bit 0
// upper u half, bit 1 upper v half, bit 2 upper depth half).
inline unsigned octant(uint32_t u, uint32_t v, uint32_t step, uint32_t half) {
  return unsigned((u & half) != 0) | unsigned((v & half) != 0) << 1 | unsigned((step & half) != 0) << 2;
}

}  // namespace

// Inlined into the walks: a call per level cost 2-5% of a point lookup.
[[gnu::always_inline]] inline const uint8_t* CpvsTileView::child_node(unsigned level, const uint8_t* node,
                                                                      uint16_t codes, unsigned child) const {
  return level_begin_[level + 1] + leaf_ref(level, node, codes, child);
}

[[gnu::always_inline]] inline uint32_t CpvsTileView::leaf_ref(unsigned level, const uint8_t* node, uint16_t codes,
                                                               unsigned child) const {
  const unsigned width = ref_width_[level];
  return cpvs::load_ref(node + 2 + width * cpvs::ref_rank(codes, child), width);
}

Result<CpvsTileView> CpvsTileView::parse(std::span<const uint8_t> payload, const CpvsParseOptions& options) {
  const uint8_t* p = payload.data();
  if (payload.size() < cpvs::kHeaderBytes) return corrupt("shorter than its header");
  if (std::memcmp(p + cpvs::kOffMagic, cpvs::kMagic, 4) != 0) return corrupt("bad magic");
  if (uint16_t version = bytes::load_le<uint16_t>(p + cpvs::kOffVersion); version != cpvs::kFormatVersion)
    return make_error(ErrorCode::unsupported, "cpvs payload: format version " + std::to_string(version));
  CpvsTileView view;
  uint8_t layout = p[cpvs::kOffLayout];
  if (layout > uint8_t(cpvs::LeafLayout::slab8)) return corrupt("unknown leaf layout");
  view.layout_ = cpvs::LeafLayout(layout);
  view.root_code_ = p[cpvs::kOffRootCode];
  if (view.root_code_ > cpvs::kCodeRef) return corrupt("bad root code");
  view.tile_size_ = bytes::load_le<uint32_t>(p + cpvs::kOffTileSize);
  view.depth_steps_ = bytes::load_le<uint32_t>(p + cpvs::kOffDepthSteps);
  const uint32_t n = view.depth_steps_;
  if (!std::has_single_bit(n) || n < cpvs::kMinSide || n > cpvs::kMaxDepthSteps) return corrupt("bad depth steps");
  if (!std::has_single_bit(view.tile_size_) || view.tile_size_ > n) return corrupt("bad tile size");
  view.level_count_ = bytes::load_le<uint32_t>(p + cpvs::kOffLevelCount);
  if (view.level_count_ != cpvs::level_count_for(n)) return corrupt("level count does not match depth steps");
  const uint64_t leaf_count = bytes::load_le<uint32_t>(p + cpvs::kOffLeafCount);

  const unsigned levels = view.level_count_;
  uint64_t at = cpvs::kHeaderBytes + uint64_t(levels) * cpvs::kLevelEntryBytes;
  if (payload.size() < at) return corrupt("truncated level table");
  std::vector<uint64_t> level_bytes(levels);
  view.ref_width_.resize(levels);
  for (unsigned l = 0; l < levels; ++l) {
    const uint8_t* entry = p + cpvs::kHeaderBytes + l * cpvs::kLevelEntryBytes;
    level_bytes[l] = bytes::load_le<uint32_t>(entry);
    view.ref_width_[l] = entry[4];
    if (entry[4] < 1 || entry[4] > 4 || entry[5] || entry[6] || entry[7]) return corrupt("bad level table entry");
    view.level_begin_.push_back(p + at);
    at += level_bytes[l];
  }
  view.leaves_ = p + at;
  if (at + leaf_count * 8 != payload.size()) return corrupt("sizes do not add up to the payload size");
  if (view.root_code_ != cpvs::kCodeRef) {
    for (uint64_t b : level_bytes)
      if (b) return corrupt("a constant tile with nodes");
    if (leaf_count) return corrupt("a constant tile with leaves");
  }

  // Bottom-up, so each level's refs can be checked against the node starts of the level below.
  std::vector<bool> starts_below;
  for (unsigned l = levels; l-- > 0;) {
    const bool last = l + 1 == levels;
    const unsigned width = view.ref_width_[l];
    const uint8_t* region = view.level_begin_[l];
    const uint64_t bytes = level_bytes[l];
    std::vector<bool> starts(bytes, false);
    for (uint64_t pos = 0; pos < bytes;) {
      if (bytes - pos < 2) return corrupt("truncated node");
      starts[pos] = true;
      uint16_t codes = bytes::load_le<uint16_t>(region + pos);
      if (cpvs::has_invalid_code(codes)) return corrupt("invalid child code");
      const unsigned refs = cpvs::ref_count(codes);
      pos += 2;
      if (bytes - pos < uint64_t(refs) * width) return corrupt("truncated node refs");
      for (unsigned i = 0; i < refs; ++i, pos += width) {
        uint32_t ref = cpvs::load_ref(region + pos, width);
        bool ok = last ? ref < leaf_count : ref < starts_below.size() && starts_below[ref];
        if (!ok) return corrupt("ref out of range or not at a node start");
      }
      ++view.stats_.nodes;
    }
    starts_below = std::move(starts);
  }
  if (view.root_code_ == cpvs::kCodeRef) {
    // Level 0 holds exactly the root node, at offset 0.
    if (levels == 0 || level_bytes[0] < 2) return corrupt("missing root node");
    const unsigned root_refs = cpvs::ref_count(bytes::load_le<uint16_t>(view.level_begin_[0]));
    if (level_bytes[0] != 2 + uint64_t(root_refs) * view.ref_width_[0])
      return corrupt("root level holds more than the root");
  }
  view.stats_.header_bytes = cpvs::kHeaderBytes + uint64_t(levels) * cpvs::kLevelEntryBytes;
  view.stats_.leaves = leaf_count;
  view.stats_.leaf_bytes = leaf_count * 8;
  view.stats_.node_bytes = payload.size() - view.stats_.header_bytes - view.stats_.leaf_bytes;

  // Skip table: the deepest level above the last whose table costs at most an eighth of the payload
  // (the table grows 8x per level: cells in u, v and depth), so a point lookup skips the top levels'
  // dependent reads. Built by walking every cell's corner down from the root.
  if (view.root_code_ == cpvs::kCodeRef) {
    const unsigned log_n = unsigned(std::countr_zero(n));
    auto entries = [&](unsigned s) {
      const uint64_t side = std::max<uint64_t>(1, uint64_t(view.tile_size_) >> (log_n - s));
      return side * side << s;
    };
    unsigned S = 0;
    for (unsigned s = 1; s + 1 < levels && s <= options.max_skip_level; ++s)
      if (entries(s) * sizeof(uint32_t) * 8 <= payload.size()) S = s;
    if (S > 0) {
      view.skip_level_ = S;
      view.skip_shift_ = log_n - S;
      view.skip_side_ = std::max<uint32_t>(1, view.tile_size_ >> view.skip_shift_);
      view.skip_.resize(entries(S));
      for (uint32_t z = 0; z < (uint32_t(1) << S); ++z)
        for (uint32_t y = 0; y < view.skip_side_; ++y)
          for (uint32_t x = 0; x < view.skip_side_; ++x) {
            const uint32_t u = x << view.skip_shift_, v = y << view.skip_shift_, step = z << view.skip_shift_;
            const uint8_t* node = view.level_begin_[0];
            uint32_t entry = 0, half = n / 2;
            for (unsigned level = 0; level < S; ++level, half /= 2) {
              const uint16_t codes = bytes::load_le<uint16_t>(node);
              const unsigned child = octant(u, v, step, half);
              const unsigned code = cpvs::child_code(codes, child);
              if (code != cpvs::kCodeRef) {
                entry = code == cpvs::kCodeLit ? kSkipLit : kSkipShadowed;
                break;
              }
              node = view.child_node(level, node, codes, child);
              entry = uint32_t(node - view.level_begin_[level + 1]);
            }
            view.skip_[view.skip_index(u, v, step)] = entry;
          }
    }
  }
  return view;
}

bool CpvsTileView::lit_at_step(uint32_t u, uint32_t v, uint32_t step) const {
  if (root_code_ != cpvs::kCodeRef) return root_code_ == cpvs::kCodeLit;
  const uint8_t* node = level_begin_[0];
  uint32_t half = depth_steps_ / 2;
  unsigned level = 0;
  if (skip_level_ != 0) {
    const uint32_t entry = skip_[skip_index(u, v, step)];
    if (entry >= kSkipShadowed) return entry == kSkipLit;
    level = skip_level_;
    node = level_begin_[level] + entry;
    half = depth_steps_ >> (level + 1);
  }
  for (;; ++level, half /= 2) {
    const bool last = level + 1 == level_count_;
    const uint16_t codes = bytes::load_le<uint16_t>(node);
    const unsigned child = last && layout_ == cpvs::LeafLayout::slab8
                               ? (step & 7u)
                               : octant(u, v, step, half);
    const unsigned code = cpvs::child_code(codes, child);
    if (code != cpvs::kCodeRef) return code == cpvs::kCodeLit;
    if (!last) {
      node = child_node(level, node, codes, child);
      continue;
    }
    const uint64_t mask = leaf(leaf_ref(level, node, codes, child));
    const unsigned bit = layout_ == cpvs::LeafLayout::slab8 ? (u & 7u) | (v & 7u) << 3
                                                             : (u & 3u) | (v & 3u) << 2 | (step & 3u) << 4;
    return ((mask >> bit) & 1u) == 0;
  }
}

bool CpvsTileView::lit(uint32_t u, uint32_t v, float threshold) const {
  int64_t step = cpvs::depth_step(threshold, depth_steps_);
  return step == cpvs::kLitBeforeEverything || lit_at_step(u, v, uint32_t(step));
}

uint32_t CpvsTileView::lit_count(uint32_t u0, uint32_t v0, uint32_t kw, uint32_t kh, float threshold) const {
  int64_t step = cpvs::depth_step(threshold, depth_steps_);
  if (step == cpvs::kLitBeforeEverything || root_code_ == cpvs::kCodeLit) return kw * kh;
  if (root_code_ == cpvs::kCodeShadowed) return 0;
  const Box box{u0, v0, u0 + kw, v0 + kh};
  const uint32_t cu = u0 >> skip_shift_, cv = v0 >> skip_shift_;
  if (skip_level_ != 0 && (box.u1 - 1) >> skip_shift_ == cu && (box.v1 - 1) >> skip_shift_ == cv) {
    // The box lies in one skip cell (PCF kernels nearly always): start at the cell's entry.
    const uint32_t entry = skip_[skip_index(u0, v0, uint32_t(step))];
    if (entry >= kSkipShadowed) return entry == kSkipLit ? kw * kh : 0;
    return count_in(skip_level_, level_begin_[skip_level_] + entry, depth_steps_ >> skip_level_, cu << skip_shift_,
                    cv << skip_shift_, uint32_t(step), box);
  }
  return count_in(0, level_begin_[0], depth_steps_, 0, 0, uint32_t(step), box);
}

uint32_t CpvsTileView::count_in(unsigned level, const uint8_t* node, uint32_t side, uint32_t nu, uint32_t nv,
                                uint32_t step, const Box& box) const {
  const bool last = level + 1 == level_count_;
  const uint16_t codes = bytes::load_le<uint16_t>(node);
  if (last && layout_ == cpvs::LeafLayout::slab8) {
    // The node's 8x8 texels at one step: one slice child.
    const unsigned child = step & 7u;
    const uint32_t x0 = std::max(box.u0, nu) - nu, x1 = std::min(box.u1, nu + 8) - nu;
    const uint32_t y0 = std::max(box.v0, nv) - nv, y1 = std::min(box.v1, nv + 8) - nv;
    const unsigned code = cpvs::child_code(codes, child);
    if (code != cpvs::kCodeRef) return code == cpvs::kCodeLit ? (x1 - x0) * (y1 - y0) : 0;
    const uint64_t shadowed = leaf(leaf_ref(level, node, codes, child));
    return unsigned(std::popcount(~shadowed & box_mask(8, x0, x1, y0, y1)));
  }
  const uint32_t half = side / 2;
  const unsigned depth_bit = (step & half) ? 4u : 0u;
  uint32_t lit = 0;
  for (unsigned quadrant = 0; quadrant < 4; ++quadrant) {
    const uint32_t cu = nu + (quadrant & 1) * half, cv = nv + (quadrant >> 1) * half;
    const uint32_t x0 = std::max(box.u0, cu), x1 = std::min(box.u1, cu + half);
    const uint32_t y0 = std::max(box.v0, cv), y1 = std::min(box.v1, cv + half);
    if (x0 >= x1 || y0 >= y1) continue;
    const unsigned child = quadrant | depth_bit;
    const unsigned code = cpvs::child_code(codes, child);
    if (code == cpvs::kCodeLit) {
      lit += (x1 - x0) * (y1 - y0);
    } else if (code == cpvs::kCodeRef) {
      if (!last) {
        lit += count_in(level + 1, child_node(level, node, codes, child), half, cu, cv, step, box);
      } else {
        const uint64_t slice = (leaf(leaf_ref(level, node, codes, child)) >> (16 * (step & 3u))) & 0xFFFFu;
        lit += unsigned(std::popcount(~slice & box_mask(4, x0 - cu, x1 - cu, y0 - cv, y1 - cv)));
      }
    }
  }
  return lit;
}

uint32_t CpvsTileView::first_shadowed_step(uint32_t u, uint32_t v) const {
  if (root_code_ != cpvs::kCodeRef) return root_code_ == cpvs::kCodeLit ? depth_steps_ : 0;
  return first_shadowed_in(0, level_begin_[0], depth_steps_, 0, u, v);
}

uint32_t CpvsTileView::first_shadowed_in(unsigned level, const uint8_t* node, uint32_t side, uint32_t z0, uint32_t u,
                                         uint32_t v) const {
  const bool last = level + 1 == level_count_;
  const uint16_t codes = bytes::load_le<uint16_t>(node);
  if (last && layout_ == cpvs::LeafLayout::slab8) {
    const unsigned bit = (u & 7u) | (v & 7u) << 3;
    for (unsigned child = 0; child < 8; ++child) {
      const unsigned code = cpvs::child_code(codes, child);
      if (code == cpvs::kCodeShadowed) return z0 + child;
      if (code == cpvs::kCodeRef && ((leaf(leaf_ref(level, node, codes, child)) >> bit) & 1u)) return z0 + child;
    }
    return depth_steps_;
  }
  const uint32_t half = side / 2;
  const unsigned quadrant = unsigned((u & half) != 0) | unsigned((v & half) != 0) << 1;
  for (unsigned depth_half = 0; depth_half < 2; ++depth_half) {
    const unsigned child = quadrant | depth_half << 2;
    const uint32_t cz = z0 + depth_half * half;
    const unsigned code = cpvs::child_code(codes, child);
    if (code == cpvs::kCodeShadowed) return cz;
    if (code != cpvs::kCodeRef) continue;
    if (!last) {
      uint32_t found = first_shadowed_in(level + 1, child_node(level, node, codes, child), half, cz, u, v);
      if (found < depth_steps_) return found;
      continue;
    }
    const uint64_t mask = leaf(leaf_ref(level, node, codes, child));
    const unsigned bit = (u & 3u) | (v & 3u) << 2;
    for (unsigned dz = 0; dz < 4; ++dz)
      if ((mask >> (bit + 16 * dz)) & 1u) return cz + dz;
  }
  return depth_steps_;
}

}  // namespace shadowtiles
