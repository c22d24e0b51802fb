// DualDepthRenderer: per tile, one Embree ray per texel centre along the light gives the interval
// [lower, upper] of depths that shadow every receiver alike (docs/architecture.md §4):
// - lower = first hit (entry);
// - upper = where the ray leaves all closed meshes: closed-mesh hits are walked in depth order with
//   a counter (+1 front-facing, -1 back-facing); where it returns to 0 is the exit. Patches over
//   nearly closed meshes' holes (Scene::patch_triangles) count too, from the light on, but are never
//   the first hit: a ray entering through a hole facing the light first hits the mesh's inside. The exit is
//   pulled back by `exit_margin` plus the exit surface's depth change over half a texel, so receivers
//   anywhere on the exit surface within the texel (a floor under a box, the shadowed slope of a
//   hill) stay shadowed for any query bias up to that margin; with cap_exits_at_receiver_surfaces,
//   instead of that slope term, by the margin below every shadowed surface inside the texel's
//   square (silhouettes, ridges; the exit surface's own shallowest point is one of them);
// - a first hit on an open mesh, a back-facing first hit, or a counter that never returns to 0
//   before an open surface: upper = lower (conservative, never leaks light);
// - heightfield meshes bound a solid closed by the far plane: they join the counter walk, so a ray
//   entering a hill exits where it leaves the hill (receivers in the valley behind stay shadowed),
//   and a ray that stays inside terrain exits at the far plane less the exit margin (upper =
//   1 - exit_margin: receivers beyond the far plane are queried as on it);
// - no hit: [1, +inf), fully lit.
// Under the `surfaces` receiver contract (docs/receiver-contracts.md) every hit is collected, open
// ones too: upper = the second receiver surface less the margin, for any mesh; with caps, capped by
// the second layer inside the texel's square (second_layer_caps).
// The tile's BVH holds only the tile's triangles, in tile-local light space (x, y in texels from the
// tile corner, z = normalised depth), so float precision is relative to the tile, not the world.
// Each hit's depth is then re-evaluated in double from the hit triangle's global light-space plane,
// so stored depths do not depend on the tiling. One residue without exit caps: where the centre ray
// crosses an edge between two exit triangles, which one Embree reports (and so the slope term) may
// differ between tilings; lower bounds are unaffected.
// Thread safety: render() may run concurrently on several threads (each call owns its BVH).
#pragma once

#include <cstdint>
#include <span>

#include "builder/depth_interval.hpp"
#include "builder/embree_device.hpp"
#include "builder/light_space_scene.hpp"
#include "builder/second_layer_caps.hpp"
#include "codec/receiver_contract.hpp"

namespace shadowtiles {

struct DualDepthStats {
  uint64_t rays = 0;
  uint64_t hits = 0;
  uint64_t exits = 0;          // texels with upper > lower
  uint64_t triangles = 0;      // in the tile's BVH
  double bvh_seconds = 0;
  double ray_seconds = 0;  // the ray casting alone (packets, counter walk)
  double cap_seconds = 0;  // the exit-cap pass (receiver_surface_caps / second_layer_caps), when on
  // The entry rule's work, when on, not in ray_seconds: its mesh neighbours (linked before the rays),
  // the cover pass after each row's rays, and the depth gaps after the last row.
  double entry_seconds = 0;
  // The cap pass's work (the build JSON's "caps"): pairs and regions under `surfaces`, the texels
  // settled under both contracts.
  SecondLayerCapCounts caps;

  void add(const DualDepthStats& other);
};

struct DualDepthOptions {
  // Normalised depth subtracted from closed-mesh exits (see above); >= the largest query bias.
  float exit_margin = 0.0f;
  // Comparison only, never a default (docs/architecture.md §4 note): the MMH authors' rule, where a ray whose
  // first hit is an open surface exits at the far plane (everything behind it counts as solid). It
  // leaks light onto receivers under open surfaces; the stability suite measures how much.
  bool open_exit_at_far_plane = false;
  // Cap each exit by the shallowest surface a shadowed receiver can lie on inside the texel's square
  // (back faces of closed meshes and heightfields, open triangles), so receivers anywhere in the
  // texel, not only on its centre ray, keep raw's answer or better. Off here for the analytic tests
  // of the centre-ray rule; the build job turns it on (BuildConfig::cap_exits_at_receiver_surfaces).
  // Conservative: a back face inside another closed mesh (intersecting solids) also caps.
  bool cap_exits_at_receiver_surfaces = false;
  // Which receivers the intervals answer exactly (anywhere: today's rule; surfaces: see above).
  ReceiverContract receivers = ReceiverContract::anywhere;
  // `surfaces`: surfaces closer than this (normalised depth) are one (second_layer::coplanar_epsilon).
  float coplanar_epsilon = 1e-6f;
  // `surfaces`, the entry rule (docs/receiver-contracts.md; builder/entry_cover.hpp): the smallest
  // query bias the values must answer for (normalised depth); 0 = off. Above 0, render() also fills
  // TileIntervals::entry_lower: for a texel whose square a cover of triangles grown from its first-hit
  // triangle holds, min(first hit, the cover's largest depth over the square + entry_tolerance -
  // entry_slack), else the first hit. Any value from there up to the capped upper answers every
  // receiver at least as raw does; apply_entry_rule() moves it into the intervals.
  float entry_slack = 0.0f;
  // How much deeper than the visible surface a receiver may lie and still count as lit (normalised
  // depth; the ground truth's occlusion rays start this far off the receiver).
  float entry_tolerance = 1e-6f;
};

// A worker's tile-sized buffers, handed back between tiles: a 4096^2 tile's intervals (128 MiB) and
// caps (64 MiB) freshly allocated per tile cost their page faults every time (15 % of a build's CPU
// on this VM). Reuse changes no output.
struct RenderBuffers {
  TileIntervals intervals;  // give the previous tile's intervals back here when done with them
  std::vector<float> caps;  // kept by render()
  SecondLayerScratch second_layer;  // the `surfaces` cap pass's working buffers
};

class DualDepthRenderer {
 public:
  DualDepthRenderer(const EmbreeDevice& device, const LightSpaceScene& scene, DualDepthOptions options = {});

  // Renders `tile` of the layout; a tile without triangles returns all misses without tracing.
  // `buffers` (optional): storage to reuse, see RenderBuffers.
  Result<TileIntervals> render(TileCoord tile, DualDepthStats* stats = nullptr, RenderBuffers* buffers = nullptr) const;
  // The texel-centre intervals alone: the exit caps not applied (though, with caps on, without the
  // slack term the caps replace). verify applies its own brute-force caps to these.
  Result<TileIntervals> render_centre(TileCoord tile, DualDepthStats* stats = nullptr,
                                      RenderBuffers* buffers = nullptr) const;
  // Whether render() applies exit caps (on, and not the far-plane comparison rule).
  bool caps_apply() const;

 private:
  const EmbreeDevice& device_;
  const LightSpaceScene& scene_;
  DualDepthOptions options_;
};

// upper = max(lower, min(upper, cap - margin)) for every hit texel with an exit (caps per texel, row-major).
void apply_exit_caps(TileIntervals& intervals, std::span<const float> caps, float exit_margin);
// DualDepthOptions::entry_tolerance for a map `frame` of a scene with `bounds`: the ground truth's
// ray offset (builder/ground_truth.hpp) in normalised depth, plus the same-surface tolerance.
double entry_tolerance_depth(const LightFrame& frame, const WorldBounds& bounds);
// apply_entry_rule: builder/depth_interval.hpp.

}  // namespace shadowtiles
