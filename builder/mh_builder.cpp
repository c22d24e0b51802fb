#include "builder/mh_builder.hpp"

#include <algorithm>
#include <bit>
#include <limits>
#include <string>

#include "builder/mh_dense_levels.hpp"
#include "builder/mh_top_down.hpp"
#include "common/isa_clones.hpp"

namespace shadowtiles {

namespace {

Status invalid(const std::string& message) {
  return Status(make_error(ErrorCode::invalid_input, "MH build: " + message));
}

// The checks that need no pass over the texels.
Status check_tile_shape(const TileIntervals& tile) {
  if (tile.size == 0 || tile.size > 16384 || !std::has_single_bit(tile.size))
    return invalid("tile size " + std::to_string(tile.size) + " is not a power of two in [1, 16384]");
  if (tile.texels.size() != size_t(tile.size) * tile.size) return invalid("texel count does not match the size");
  if (!tile.entry_lower.empty() && tile.entry_lower.size() != tile.texels.size())
    return invalid("entry-rule bound count does not match the size");
  return Status::success();
}

// Finite and not NaN, without a branch (the checks below vectorise or ride the bottom level's reads).
bool finite_float(float x) { return (std::bit_cast<uint32_t>(x) & 0x7f800000u) != 0x7f800000u; }
bool bad_interval(const DepthInterval& t) { return !finite_float(t.lower) | !(t.lower <= t.upper); }

}  // namespace

Status check_tile_intervals(const TileIntervals& tile) {
  if (Status s = check_tile_shape(tile); !s) return s;
  const bool entry = !tile.entry_lower.empty();
  // A pass without a branch first (it vectorises); the loop names the first bad texel only when
  // there is one.
  bool bad = false;
  for (const DepthInterval& t : tile.texels) bad |= bad_interval(t);
  if (entry)
    for (float bound : tile.entry_lower) bad |= !finite_float(bound);
  if (!bad) return Status::success();
  for (size_t i = 0; i < tile.texels.size(); ++i) {
    if (entry && !finite_float(tile.entry_lower[i]))
      return invalid("texel " + std::to_string(i) + " has an invalid entry-rule bound " +
                     std::to_string(tile.entry_lower[i]));
    const DepthInterval& t = tile.texels[i];
    if (bad_interval(t))
      return invalid("texel " + std::to_string(i) + " has an invalid interval [" + std::to_string(t.lower) + ", " +
                     std::to_string(t.upper) + "]");
  }
  return Status::success();
}

namespace {

// `bad` is set when a texel's interval or entry bound is invalid (check_tile_intervals' rule, tested
// as the bottom level reads the texels: a separate pass over them was 2 % of an oahu 16384² build);
// the tree is then to be discarded.
SHADOWTILES_ISA_CLONES MhHierarchy build_bottom_up(const TileIntervals& tile, bool& bad) {
  const unsigned L = unsigned(std::countr_zero(tile.size));
  MhDenseLevels dense;
  dense.size = tile.size;
  dense.levels = L;
  dense.masks.resize(L);
  dense.valued.resize(L + 1);
  // The `surfaces` entry rule's bounds, when not yet applied (TileIntervals::entry_lower).
  const float* entry = tile.entry_lower.empty() ? nullptr : tile.entry_lower.data();
  if (L == 0) {
    DepthInterval only = tile.texels[0];
    bad = bad_interval(only) | (entry && !finite_float(entry[0]));
    if (entry) only.lower = std::min(only.lower, entry[0]);
    dense.valued[0] = {only};
    return to_hierarchy(std::move(dense));
  }
  constexpr float kInf = std::numeric_limits<float>::infinity();
  constexpr size_t kPrefetchAhead = 64;  // parents: 4 blocks of 4x4
  std::vector<DepthInterval> child, parent;  // intervals of levels l+1 and l, dense, Morton order
  bool any_bad = false;  // a local: `bad` through the reference would be stored per texel
  for (unsigned l = L; l-- > 0;) {
    const size_t n = size_t(1) << (2 * l);
    const bool bottom = l + 1 == L;
    parent.resize(n);
    auto& masks = dense.masks[l];
    masks.resize(n);
    const auto* child_masks = bottom ? nullptr : dense.masks[l + 1].data();
    auto& valued = dense.valued[l + 1];
    for (size_t p = 0; p < n; ++p) {
      DepthInterval c[4];
      if (bottom && p % 16 == 0 && p + kPrefetchAhead < n) {
        // Morton order jumps between rows, which the hardware prefetcher does not follow: the loads
        // of the texels waited on memory (a fifth of the build's time on dragon). Fetch the 8 rows
        // of the 8x8-texel block that the 16 parents kPrefetchAhead on will read.
        const DepthInterval* block =
            &tile.texels[size_t(2 * morton_y(p + kPrefetchAhead)) * tile.size + 2 * morton_x(p + kPrefetchAhead)];
        for (unsigned r = 0; r < 8; ++r) {
          __builtin_prefetch(block + size_t(r) * tile.size);
          __builtin_prefetch(block + size_t(r) * tile.size + 7);
          if (entry) __builtin_prefetch(entry + (block - tile.texels.data()) + size_t(r) * tile.size);
        }
      }
      if (bottom) {  // texels straight from the row-major input: a 2x2 block
        const size_t at = size_t(2 * morton_y(p)) * tile.size + 2 * morton_x(p);
        const DepthInterval* row = &tile.texels[at];
        c[0] = row[0], c[1] = row[1], c[2] = row[tile.size], c[3] = row[tile.size + 1];
        any_bad |= bad_interval(c[0]) | bad_interval(c[1]) | bad_interval(c[2]) | bad_interval(c[3]);
        if (entry) {  // apply_entry_rule's min, as the texels are read
          const float* bound = entry + at;
          any_bad |= !finite_float(bound[0]) | !finite_float(bound[1]) | !finite_float(bound[tile.size]) |
                     !finite_float(bound[tile.size + 1]);
          c[0].lower = std::min(c[0].lower, bound[0]), c[1].lower = std::min(c[1].lower, bound[1]);
          c[2].lower = std::min(c[2].lower, bound[tile.size]);
          c[3].lower = std::min(c[3].lower, bound[tile.size + 1]);
        }
      } else {
        for (unsigned i = 0; i < 4; ++i) c[i] = child[4 * p + i];
      }
      // Four children sharing a depth (misses and flat ground, where all four are equal, or a smooth
      // surface with room behind it): the largest lower is covered by all four, and only children
      // with that lower count four, so the search below would pick it and cover every child; the
      // parent is their intersection and nothing is kept. The same result without the search, on
      // most of a map (std::max and std::min keep the first of equal values, as the search does).
      const float most_lower = std::max(std::max(c[0].lower, c[1].lower), std::max(c[2].lower, c[3].lower));
      const float least_upper = std::min(std::min(c[0].upper, c[1].upper), std::min(c[2].upper, c[3].upper));
      if (most_lower <= least_upper) {
        uint8_t mask = 0;
        if (child_masks)
          for (unsigned i = 0; i < 4; ++i) mask |= uint8_t((child_masks[4 * p + i] != 0 ? 2u : 0u) << (2 * i));
        masks[p] = mask;
        parent[p] = {most_lower, least_upper};
        continue;
      }
      // The depth covered by most children is some child's lower bound; ties go to the first.
      unsigned best = 0, best_count = 0;
      for (unsigned i = 0; i < 4; ++i) {
        unsigned count = 0;
        for (unsigned j = 0; j < 4; ++j) count += c[j].lower <= c[i].lower && c[i].lower <= c[j].upper;
        if (count > best_count) best = i, best_count = count;
      }
      const float candidate = c[best].lower;
      DepthInterval interval{-kInf, kInf};
      uint8_t mask = 0;
      for (unsigned i = 0; i < 4; ++i) {
        unsigned code;
        if (c[i].lower <= candidate && candidate <= c[i].upper) {
          interval.lower = std::max(interval.lower, c[i].lower);
          interval.upper = std::min(interval.upper, c[i].upper);
          code = 0;  // covered
        } else {
          code = 1;  // keeps a value
          valued.push_back(c[i]);
        }
        if (child_masks && child_masks[4 * p + i] != 0) code |= 2;  // has kept descendants
        mask |= uint8_t(code << (2 * i));
      }
      masks[p] = mask;
      parent[p] = interval;
    }
    child.swap(parent);
  }
  bad = any_bad;
  dense.valued[0] = {child[0]};
  return to_hierarchy(std::move(dense));
}

}  // namespace

Result<MhHierarchy> build_mh(const TileIntervals& tile, const MhBuildOptions& options) {
  if (options.construction == MhConstruction::top_down) {
    if (Status s = check_tile_intervals(tile); !s) return s.error();
    if (tile.entry_lower.empty()) return build_mh_top_down(tile);
    TileIntervals applied = tile;
    apply_entry_rule(applied);
    return build_mh_top_down(applied);
  }
  if (Status s = check_tile_shape(tile); !s) return s.error();
  bool bad = false;
  MhHierarchy built = build_bottom_up(tile, bad);
  if (bad) {  // the full check names the first bad texel (it tests the same rule)
    Status s = check_tile_intervals(tile);
    return s ? make_error(ErrorCode::invalid_input, "MH build: an invalid texel interval") : s.error();
  }
  return built;
}

}  // namespace shadowtiles
