// Synthetic scenes of the stability suite (issue #8), written as OBJ files so they go through the
// same loader and build job as real scenes. z up, metres; every face counter-clockwise seen from
// outside (or from above for one-sided quads).
// Errors: io_error when the file cannot be written. Thread safety: pure functions.
#pragma once

#include <filesystem>

#include "common/result.hpp"

namespace shadowtiles::bench {

// A 20 x 20 floor (one-sided quad facing up) and a room over its middle: four one-sided wall quads
// and a one-sided roof quad (10 x 10 at height 3). Every mesh is open: the roof's texels must keep
// entry = exit, or the floor under it is lit.
Status write_open_roof_room(const std::filesystem::path& file);

// A 40 x 40 floor (one-sided, facing up) with one closed wall (a box 10 long, 4 high, `thickness`
// thick along x) across its middle, meant to be lit from the east or west so it casts a long
// shadow on the floor.
Status write_thin_wall(const std::filesystem::path& file, double thickness);
// The bounds of write_thin_wall's scene (independent of the thickness), to fit a light frame
// before choosing the thickness in texels.
struct SyntheticBounds {
  double min[3], max[3];
};
SyntheticBounds thin_wall_bounds();

// Scenes of the `surfaces` receiver contract's rows (scenario 9), each over a one-sided 20 x 20 floor:
// - roof_inner_wall: a one-sided roof (10 x 10 at height 3) on no walls, and an inside wall quad whose
//   top (2.9) lies just under the roof: the docs' counter-example to the centre-ray rule;
// - leaf: one single-sided tilted quad (a leaf) at height 2 to 2.5;
// - stacked_shells: two open boxes without bottoms (8 x 8 x 4 around 4 x 4 x 2);
// - open_wall: one single-sided vertical quad (10 long, 4 high, no thickness) across the floor.
Status write_surfaces_scene(const std::filesystem::path& file, const std::string& which);

// One triangle of about `size` world units (a single-triangle scene).
Status write_single_triangle(const std::filesystem::path& file, double size);

}  // namespace shadowtiles::bench
