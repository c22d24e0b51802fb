// MH construction for one tile (docs/architecture.md §5; SBE16a): from per-texel depth intervals to an
// MhHierarchy whose every texel resolves to a value inside its interval.
//
// Bottom-up (default): one level at a time from the texels to the root, over dense Morton-order
// arrays (about 1.4 bytes per texel besides the input, plus the valued nodes' intervals). Per
// parent the candidate is the lower bound of the child interval that the most children's intervals
// contain (ties: the first child in child order); the parent interval is the intersection of the
// children containing it. Those children are covered: with no kept descendants they vanish, with
// some they become empty nodes; the others keep a value. A node's interval is exactly the set of
// values valid for the texels that resolve to it, so every level is a complete shadow map and each
// coarse value is exact for at least one texel below it.
// Top-down (SBE16a Alg. 1, option): mh_top_down.hpp. Slower (O(n log n) per level).
//
// Works on any power-of-two grid of intervals, e.g. the tiles' root intervals for the top levels.
// A tile whose entry-rule bounds are not yet applied (TileIntervals::entry_lower non-empty) is built
// as apply_entry_rule would leave it, without that copy of the tile (the bottom-up build takes the
// min as it reads the texels).
// Errors: invalid_input when the size is not a power of two in [1, 16384], the texel count does
// not match, or an interval is not [finite lower, upper >= lower] (upper may be +inf), or the
// entry-rule bounds are not one finite value per texel.
// Thread safety: pure function; independent calls may run concurrently.
#pragma once

#include "builder/depth_interval.hpp"
#include "builder/mh_hierarchy.hpp"
#include "common/result.hpp"

namespace shadowtiles {

enum class MhConstruction { bottom_up, top_down };

struct MhBuildOptions {
  MhConstruction construction = MhConstruction::bottom_up;
};

Result<MhHierarchy> build_mh(const TileIntervals& tile, const MhBuildOptions& options = {});

// Input validation: finite lowers, lower <= upper, finite entry-rule bounds, one per texel. The
// top-down build runs it first; the bottom-up build tests the same rule as it reads the texels and
// runs this only to name the first bad texel.
Status check_tile_intervals(const TileIntervals& tile);

}  // namespace shadowtiles
