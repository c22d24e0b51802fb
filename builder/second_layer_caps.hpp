// Exit caps of the `surfaces` receiver contract (docs/receiver-contracts.md): per texel, the
// shallowest depth, inside the texel's square, of the scene's second layer, the parts of surfaces
// that lie behind another surface (by more than the coplanar epsilon) along the light. Every
// receiver a shadow map must shadow lies there, so an upper bound of cap - margin keeps every one of
// them shadowed, wherever it sits in the texel. Any mesh counts, closed or not: a closed mesh's back
// faces are behind its front faces; a floor under a one-sided roof is behind the roof.
//
// How: triangle pairs whose footprint boxes overlap (a uniform grid of the boxes, each pair once) give
// the convex region of T behind T': T clipped by T''s edges and by z_T - z_T' >= epsilon, exactly in
// double; and the near-cover region, z_T - z_T' in [kSameSurface, epsilon], which counts per texel
// only below the texel's lower + second_layer::near_cover_offset (clipped per texel by that floor).
// A pair with a small box goes to the clips only when, in some texel of it, both triangles' planes
// leave room for a region point (at or below the floor, for near cover) that could still lower the
// cap and the interval. Each region's triangle fan lowers the caps of the texels it touches through
// lower_caps_by_triangle (exact per-texel clipping, closed form inside). The occluder's edges are
// widened by 2^-20 texels and the epsilon narrowed by 2^-20 of itself so that the region found here
// contains the exact one despite rounding: the caps are never above verify's brute-force reference.
// Where a sharp corner's widened edges meet far outside the occluder's box (slivers), the region is
// also clipped to that box padded by 1/256 texel, so it stays near the occluder.
// Edge-on triangles (second_layer::edge_on) cover no area: they hide nothing and cap by their own
// shallowest point. A pair is dropped before any clipping when an edge of either triangle separates
// them, when `back` is behind `front` by less than kSameSurface wherever it meets a widened edge of
// `front` (mesh neighbours: the part of `back` a widened edge keeps is a sliver along a shared edge
// or vertex), or when `back`'s plane lies nowhere behind `front`'s over the box the clips could keep
// (the depth gap is linear, so its corners bound it): the regions found are the same.
// Why not Embree's rtcCollide: it hands pairs to a callback under a lock on worker threads, and a
// city tile has tens of millions of pairs; the grid visits them in place (honolulu 16K: caps
// thread-seconds 8.4 -> 5.4, stores byte-identical).
// Thread safety: pure function.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "builder/depth_interval.hpp"
#include "builder/light_space_scene.hpp"
#include "builder/receiver_surface_caps.hpp"

namespace shadowtiles {

struct SecondLayerCapCounts {
  uint64_t pairs_tested = 0;   // footprint-overlapping pairs that passed the depth test
  uint64_t regions = 0;        // non-empty regions behind another triangle by the coplanar epsilon
  uint64_t near_regions = 0;   // non-empty regions behind it by less (near cover)
  uint64_t skipped = 0;        // pairs or regions that could not change a capped interval (pairs
                               // apart across an edge are counted in neither)
  ReceiverCapCounts texels;    // how the regions' texels were resolved

  void add(const SecondLayerCapCounts& other) {
    pairs_tested += other.pairs_tested, regions += other.regions, near_regions += other.near_regions;
    skipped += other.skipped;
    texels.add(other.texels);
  }
};

// Working buffers second_layer_caps keeps between tiles: on a city or terrain tile they hold about
// 10 MB, and fresh pages cost a fault each (41 % of an oahu `surfaces` build's faults came from here).
class SecondLayerScratch {
 public:
  SecondLayerScratch();
  ~SecondLayerScratch();
  SecondLayerScratch(SecondLayerScratch&&) noexcept;
  SecondLayerScratch& operator=(SecondLayerScratch&&) noexcept;

  struct Buffers;  // defined where it is used
  Buffers& buffers();  // allocated at first use

 private:
  std::unique_ptr<Buffers> buffers_;
};

// The cap per texel of `tile` (+inf where no second layer lies in the square); `coplanar_epsilon` in
// normalised depth (second_layer::coplanar_epsilon). `intervals` (the tile's centre intervals) give
// each texel's lower for the near-cover floor; with the exit margin, regions that cannot change
// apply_exit_caps' result anywhere in their box are skipped: float(shallowest) - margin >= every
// texel's upper there, or (texel by texel, for small boxes) no lower than the cap found so far
// (texels without an exit have nothing to cap). The caps are then exact only where they matter;
// apply_exit_caps gives the same intervals as with every region.
// `storage`: a buffer to reuse (as receiver_surface_caps); `reuse`: working buffers to reuse.
// `texel_tests`: false sends every small box to the clips too, for the tests that check the
// texel-by-texel prune changes no interval.
std::vector<float> second_layer_caps(const LightSpaceScene& scene, TileCoord tile, double coplanar_epsilon,
                                     const TileIntervals& intervals, float exit_margin,
                                     SecondLayerCapCounts* counts = nullptr, std::vector<float> storage = {},
                                     SecondLayerScratch* reuse = nullptr, bool texel_tests = true);

}  // namespace shadowtiles
