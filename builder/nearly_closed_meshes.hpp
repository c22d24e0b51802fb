// Nearly closed meshes (issue #14, docs/receiver-contracts.md "Nearly closed solids"): scans with a few
// holes, meshes with a few non-manifold edges, accepted as solids under the `anywhere` contract.
//
// A mesh's boundary, as a chain, is the sum of its edges' net directions (an undirected edge used f times
// one way and g times the other contributes f - g copies of it; a closed mesh's boundary is zero). The
// boundary is always a union of closed directed loops. Each loop gets an explicit patch, a fan from the
// loop's centroid oriented against the loop, so mesh + patches is a 2-cycle: its winding number is an
// integer everywhere off its surface and a ray's front/back counter computes it exactly, whatever the
// holes, non-manifold or misoriented edges. Soundness of the counter therefore comes from construction.
//
// Acceptance is the semantic question: is the region mesh + patches bounds what a user calls the solid?
// The generalized winding number of the open mesh (Jacobson et al. 2013) is w = w_cycle - w_patch with
// w_cycle an integer, so its departure from the patched solid's integer winding is exactly |w_patch|,
// computed over the few patch triangles only. At sample points just off the surface (each sampled
// triangle's centroid offset by +-eps along its normal) the mesh is accepted when
//   - the area of the surface where |w_patch| > tolerance is at most max_ambiguous_area of the mesh's
//     area (holes seen at a wide solid angle from much of the surface, flipped faces and patches that
//     cut through the mesh all make |w_patch| large there), and
//   - mesh + patches has positive volume (outward-facing: an inside-out solid gives no exit anyway), and
//   - its whole winding number (mesh + patches, every triangle) is 0 just outside and 1 just inside on
//     all but at most max_misplaced_area of a subset of the samples (at least min_full_samples): a
//     surface lying inside its own solid (faces between touching parts, overlapping parts, a scan's
//     folds and inner sheets) or a flipped face is no receiver place once the mesh is a solid; where
//     that is a large share of the surface (touching IFC parts), real receivers lie there, so such a
//     mesh stays open.
// A mesh accepted this way becomes MeshKind::closed; its patch triangles live in Scene::patch_triangles,
// where only the exit counter and the exit caps see them (never a first hit, never a receiver or an
// occluder: builder/dual_depth_renderer, builder/receiver_surface_caps, builder/reference_caps).
//
// Cost: O(sampled triangles x patch triangles) solid angles per mesh, samples capped at max_samples,
// plus the whole winding numbers of the full samples through a WindingNumberTree (hierarchical:
// about a boundary's worth of solid angles per node near the point, not one per triangle)
// (area-stratified, deterministic). Thread safety: pure functions. Untrusted input: safe (indices come
// from Scene::add_mesh, which checked them).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "builder/scene.hpp"
#include "codec/store_meta.hpp"

namespace shadowtiles {

struct NearlyClosedOptions {
  // |w_patch| above this at a sample marks its area ambiguous. 0.1: the patched solid then agrees with
  // the generalized winding number's own segmentation (w >= 1/2) with a margin of 0.4 at the samples.
  double tolerance = 0.1;
  // Largest share of the mesh's area whose samples may be ambiguous (the rims of small holes at a
  // crease see the patch at up to a quarter of the sphere whatever the hole's size).
  double max_ambiguous_area = 0.01;
  // Sample triangles per mesh (all of them below this count).
  uint32_t max_samples = 8192;
  // A mesh whose boundary loops need more patch triangles than this is refused without the w test
  // (bounds the cost: samples x patch triangles solid angles).
  uint32_t max_patch_triangles = 20000;
  // The whole winding number (every triangle) is computed on at least this many samples (all of them
  // when fewer), more while samples x triangles stays within full_budget solid angles per side.
  uint32_t min_full_samples = 512;
  uint64_t full_budget = 20000000;
  // Largest share of the whole-w samples' area where the winding number is wrong. 0.01, the same
  // budget as max_ambiguous_area: dragon_res2's folds and inner sheets are 0.8 % (4 of 512 samples);
  // the fzk_haus meshes refused for faces between touching parts are 2.6-88 %. 0 refuses any.
  double max_misplaced_area = 0.01;
  // Threads for the winding numbers at the samples (not a test parameter: the result is the same for
  // any count).
  unsigned threads = 1;
};

// One open mesh's test, for the log and the build summary.
struct MeshClosingReport {
  uint32_t mesh = 0;
  bool accepted = false;
  std::string reason;               // why refused (empty when accepted)
  uint64_t boundary_edges = 0;      // as MeshInfo
  uint64_t non_manifold_edges = 0;
  uint64_t misoriented_edges = 0;
  uint32_t loops = 0;               // boundary loops patched
  uint32_t patch_triangles = 0;
  uint32_t samples = 0;
  double max_deviation = 0;         // max |w_patch| over the samples (both sides)
  double ambiguous_area = 0;        // share of the area whose samples exceed the tolerance
  double patched_volume = 0;        // signed volume of mesh + patches
  uint32_t full_samples = 0;        // samples where the whole winding number was computed
  uint32_t misplaced_samples = 0;   // ... where it is not 0 outside and 1 inside
  double misplaced_area = 0;        // their share of the full samples' area (refused above the option)
};

struct NearlyClosedReport {
  std::vector<MeshClosingReport> meshes;  // every open mesh tested
  uint64_t accepted_meshes = 0;
  uint64_t accepted_triangles = 0;
  uint64_t patch_triangles = 0;
};

// The patch of a mesh's boundary (triangles over `vertices` plus the loops' centroids, appended to
// `vertices`), or none when the mesh is closed. Exposed for the tests.
struct MeshPatch {
  std::vector<std::array<uint32_t, 3>> triangles;
  uint32_t loops = 0;
};
MeshPatch patch_boundary_loops(std::vector<Vec3>& vertices, std::span<const std::array<uint32_t, 3>> triangles);

// Generalized winding number at `p` of the triangles (sum of signed solid angles / 4 pi): 1 inside a
// closed outward-oriented mesh, 0 outside.
double winding_number(const std::vector<Vec3>& vertices, std::span<const std::array<uint32_t, 3>> triangles,
                      const Vec3& p);

// Tests every open (not heightfield) mesh of `scene`; accepted meshes become closed and their patches are
// appended to scene.patch_triangles / patch_mesh (centroids to scene.vertices). Logs one line per mesh
// tested and a summary (spdlog info).
NearlyClosedReport close_nearly_closed_meshes(Scene& scene, const NearlyClosedOptions& options);

// The options a store was built with (its meta), to close a scene the way its build did.
inline NearlyClosedOptions nearly_closed_options(const StoreMeta& meta) {
  NearlyClosedOptions options;
  options.tolerance = meta.nearly_closed_tolerance;
  options.max_ambiguous_area = meta.nearly_closed_max_ambiguous_area;
  options.max_samples = meta.nearly_closed_max_samples;
  options.max_patch_triangles = meta.nearly_closed_max_patch_triangles;
  options.min_full_samples = meta.nearly_closed_min_full_samples;
  options.full_budget = meta.nearly_closed_full_budget;
  options.max_misplaced_area = meta.nearly_closed_max_misplaced_area;
  return options;
}

}  // namespace shadowtiles
