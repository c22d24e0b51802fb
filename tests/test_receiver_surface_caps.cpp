// Receiver-surface exit caps (issue #8): the fast row-span / closed-form caps equal, bit for bit, the
// original per-texel clipping of every texel of the triangle's bounding box, kept here as reference,
// on synthetic triangles (sizes, orientations, slivers, vertices on texel borders, larger than or
// partly outside the window, depths on float rounding midpoints) and on real scene tiles.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "builder/dual_depth_renderer.hpp"
#include "builder/embree_device.hpp"
#include "builder/receiver_surface_caps.hpp"
#include "receiver_surface_caps_reference.hpp"

namespace shadowtiles {
namespace {

using testing::differing_texels;
using testing::expect_scene_identical;
using testing::reference_lower_caps;


struct Triangle {
  LightSpacePoint a, b, c;
};

// Compares one triangle's caps, fast vs reference, on a fresh window; returns the texels that differ
// and how many texels it caps at all.
size_t compare(const Triangle& t, const TexelWindow& window, ReceiverCapCounts& counts, size_t* capped = nullptr) {
  const float inf = std::numeric_limits<float>::infinity();
  std::vector<float> fast(size_t(window.size) * window.size, inf), reference = fast;
  lower_caps_by_triangle(t.a, t.b, t.c, window, fast, &counts);
  reference_lower_caps(t.a, t.b, t.c, window, reference);
  if (capped)
    *capped += size_t(std::count_if(reference.begin(), reference.end(), [](float f) { return !std::isinf(f); }));
  return differing_texels(fast, reference);
}

// Random triangles around a window at global texel (u0, v0): `make` draws one.
template <class Make>
void expect_identical(const char* what, int count, const TexelWindow& window, Make make,
                      ReceiverCapCounts* total = nullptr) {
  ReceiverCapCounts counts;
  size_t differing = 0, differing_triangles = 0, capped = 0;
  for (int n = 0; n < count; ++n) {
    const size_t d = compare(make(), window, counts, &capped);
    differing += d;
    differing_triangles += d != 0;
  }
  EXPECT_EQ(differing, 0u) << what << ": " << differing_triangles << " of " << count << " triangles differ";
  EXPECT_GT(capped, 0u) << what << ": the triangles must reach the window";
  if (total) {
    total->clipped += counts.clipped;
    total->interior += counts.interior;
    total->fallback += counts.fallback;
    total->corner += counts.corner;
    total->chord += counts.chord;
  }
}

constexpr TexelWindow kWindow{4096, 12288, 64};  // global coordinates, as a tile far from the origin

class Draw {
 public:
  explicit Draw(uint64_t seed) : rng_(seed) {}
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng_); }
  double log_uniform(double lo, double hi) { return std::exp(uniform(std::log(lo), std::log(hi))); }
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }
  // A point around the window (margin texels beyond each side).
  LightSpacePoint around(const TexelWindow& w, double margin) {
    return {w.u0 + uniform(-margin, w.size + margin), w.v0 + uniform(-margin, w.size + margin), uniform(0.05, 0.95)};
  }
  // A triangle of scale `size` around `centre`, any orientation and winding, depths on a random plane.
  Triangle around_point(const LightSpacePoint& centre, double size) {
    const double gu = uniform(-1, 1) / std::max(size, 1.0) * 0.3, gv = uniform(-1, 1) / std::max(size, 1.0) * 0.3;
    auto vertex = [&] {
      const double angle = uniform(0, 2 * std::numbers::pi), radius = size * uniform(0.2, 1.0);
      const double u = centre.u + radius * std::cos(angle), v = centre.v + radius * std::sin(angle);
      return LightSpacePoint{u, v, centre.depth + gu * (u - centre.u) + gv * (v - centre.v)};
    };
    return {vertex(), vertex(), vertex()};
  }

 private:
  std::mt19937_64 rng_;
};

// Many triangles lowering one window, as a tile's overlapping surfaces do: texels whose cap is already
// at or below a triangle's shallowest vertex are skipped unclipped, and the window must still equal
// the reference's, bit for bit, with the skip taken.
TEST(ReceiverSurfaceCaps, OverlappingTrianglesSkipTexelsAlreadyLowerAndStillMatch) {
  Draw draw(3);
  const float inf = std::numeric_limits<float>::infinity();
  std::vector<float> fast(size_t(kWindow.size) * kWindow.size, inf), reference = fast;
  ReceiverCapCounts counts;
  for (int n = 0; n < 3000; ++n) {
    const Triangle t = draw.around_point(draw.around(kWindow, 2), draw.log_uniform(0.3, 6));
    lower_caps_by_triangle(t.a, t.b, t.c, kWindow, fast, &counts);
    reference_lower_caps(t.a, t.b, t.c, kWindow, reference);
  }
  EXPECT_EQ(differing_texels(fast, reference), 0u);
  EXPECT_GT(counts.already_lower, 0u) << "overlapping triangles must exercise the skip";
  EXPECT_LT(counts.already_lower, counts.clipped + counts.fallback) << "and some texels are still clipped";
}

TEST(ReceiverSurfaceCaps, RandomTrianglesOfAllSizesMatchTheClipping) {
  Draw draw(1);
  ReceiverCapCounts counts;
  expect_identical("random", 6000, kWindow, [&] {
    return draw.around_point(draw.around(kWindow, 8), draw.log_uniform(0.01, 300));
  }, &counts);
  // The fast path must be the one mostly taken on large triangles, and the fallback rare.
  EXPECT_GT(counts.interior, counts.clipped);
  EXPECT_LT(counts.fallback * 100, counts.interior);
  // Edge texels whose shallowest corner is inside take the closed form too, and still match.
  EXPECT_GT(counts.corner * 4, counts.clipped);
  EXPECT_GT(counts.chord * 4, counts.clipped);
  std::printf("clipped %llu (closed form at a corner %llu, on a chord %llu), interior %llu, fallback %llu\n",
              (unsigned long long)counts.clipped, (unsigned long long)counts.corner,
              (unsigned long long)counts.chord, (unsigned long long)counts.interior,
              (unsigned long long)counts.fallback);
}

TEST(ReceiverSurfaceCaps, SliversAndDegenerateTrianglesMatchTheClipping) {
  Draw draw(2);
  expect_identical("slivers", 3000, kWindow, [&] {
    // Two far vertices and a third a hair off their segment (or on it: zero area).
    LightSpacePoint p = draw.around(kWindow, 20), q = draw.around(kWindow, 20);
    const double t = draw.uniform(0, 1), offset = draw.integer(0, 3) == 0 ? 0.0 : draw.log_uniform(1e-12, 0.5);
    const double du = q.u - p.u, dv = q.v - p.v, length = std::hypot(du, dv) + 1e-300;
    LightSpacePoint r{p.u + t * du - offset * dv / length, p.v + t * dv + offset * du / length,
                      draw.uniform(0.05, 0.95)};
    return Triangle{p, q, r};
  });
  expect_identical("coincident vertices", 500, kWindow, [&] {
    LightSpacePoint p = draw.around(kWindow, 4), q = draw.around(kWindow, 4);
    return Triangle{p, q, draw.integer(0, 1) ? p : q};
  });
}

TEST(ReceiverSurfaceCaps, VerticesOnTexelBordersMatchTheClipping) {
  Draw draw(3);
  // Vertices on the texel grid (integers and halves), so edges run along texel borders and corners.
  auto on_grid = [&](double margin) {
    auto snap = [&](double x) { return draw.integer(0, 1) ? std::round(x) : std::round(2 * x) / 2; };
    LightSpacePoint p = draw.around(kWindow, margin);
    return LightSpacePoint{snap(p.u), snap(p.v), p.depth};
  };
  expect_identical("grid vertices", 4000, kWindow, [&] { return Triangle{on_grid(6), on_grid(6), on_grid(6)}; });
  expect_identical("axis-aligned right triangles", 2000, kWindow, [&] {
    LightSpacePoint p = on_grid(6), q = on_grid(6);
    LightSpacePoint r{p.u, q.v, draw.uniform(0.05, 0.95)};
    return Triangle{p, q, r};
  });
  // Small triangles sharing a grid corner: the four texels around it are all touched.
  expect_identical("around a corner", 2000, kWindow, [&] {
    LightSpacePoint corner = on_grid(0);
    corner.u = std::round(corner.u);
    corner.v = std::round(corner.v);
    Triangle t = draw.around_point(corner, draw.log_uniform(0.01, 3));
    t.a.u = corner.u;
    t.a.v = corner.v;
    return t;
  });
}

// Squares are closed (docs/receiver-contracts.md): a triangle whose leftmost vertex lies exactly on a
// tile's border caps the left tile's last column at that vertex. RealisticTerrain at 4096^2, sun
// 135,45, tiles of 1024: heightfield triangle 70378 (facing away from the light) starts on u = 2048,
// and tile 1,2's texel 1023,15 was left uncapped (upper 0.947 where the reference caps it to its lower).
TEST(ReceiverSurfaceCaps, TriangleStartingOnATileBorderCapsTheTexelBeforeIt) {
  const LightSpacePoint a{2063.9680638722552, 2062.0023298418832, 0.56409044442253675};
  const LightSpacePoint b{2055.9840319361278, 2063.0706339061371, 0.5601892666215702};
  const LightSpacePoint c{2048, 2063.5059144695028, 0.56361584722641489};  // on the tile border
  const float inf = std::numeric_limits<float>::infinity();
  for (const TexelWindow window : {TexelWindow{1024, 2048, 1024}, TexelWindow{2048 - 32, 2048, 32}}) {
    std::vector<float> cap(size_t(window.size) * window.size, inf);
    lower_caps_by_triangle(a, b, c, window, cap);
    const size_t last_column = window.size - 1, row = size_t(2063 - window.v0);
    EXPECT_EQ(cap[row * window.size + last_column], float(c.depth)) << "window at u " << window.u0;
    EXPECT_EQ(cap[(row - 1) * window.size + last_column], inf) << "the row below does not touch it";
  }
  // The same on the v axis and inside a window: a vertex on a texel's lower border caps the texel below.
  const LightSpacePoint p{40, 30, 0.25}, q{45, 36, 0.5}, r{38, 37, 0.75};  // p.v = 30 is the lowest v
  std::vector<float> cap(size_t(64) * 64, inf);
  lower_caps_by_triangle(p, q, r, TexelWindow{0, 0, 64}, cap);
  EXPECT_EQ(cap[size_t(29) * 64 + 40], 0.25f) << "texel 40,29 (square v in [29, 30]) holds vertex p";
  EXPECT_EQ(cap[size_t(29) * 64 + 39], 0.25f) << "texel 39,29 touches p at its corner";
}

TEST(ReceiverSurfaceCaps, TrianglesLargerThanOrPartlyOutsideTheWindowMatchTheClipping) {
  Draw draw(4);
  ReceiverCapCounts counts;
  expect_identical("larger than the window", 300, kWindow, [&] {
    return draw.around_point(draw.around(kWindow, 0), draw.log_uniform(100, 5000));
  }, &counts);
  expect_identical("partly outside", 2000, kWindow, [&] {
    // Centred on a border of the window.
    LightSpacePoint centre = draw.around(kWindow, 0);
    if (draw.integer(0, 1)) centre.u = kWindow.u0 + (draw.integer(0, 1) ? 0 : kWindow.size) + draw.uniform(-2, 2);
    else centre.v = kWindow.v0 + (draw.integer(0, 1) ? 0 : kWindow.size) + draw.uniform(-2, 2);
    return draw.around_point(centre, draw.log_uniform(0.5, 100));
  }, &counts);
  EXPECT_GT(counts.interior, 0u);
  // Steep planes: depth changes by up to the whole depth range within a texel or two.
  expect_identical("steep", 2000, kWindow, [&] {
    Triangle t = draw.around_point(draw.around(kWindow, 4), draw.log_uniform(1, 40));
    t.b.depth = draw.uniform(0, 1);
    t.c.depth = draw.uniform(0, 1);
    return t;
  });
  // A window at the map's origin and one far out (2^16 texels).
  for (TexelWindow window : {TexelWindow{0, 0, 48}, TexelWindow{65536 - 32, 65536 - 64, 32}})
    expect_identical("other windows", 1500, window, [&] {
      return draw.around_point(draw.around(window, 8), draw.log_uniform(0.05, 200));
    });
}

TEST(ReceiverSurfaceCaps, DepthsOnFloatRoundingMidpointsMatchTheClipping) {
  // Nearly flat triangles whose depth sits on the midpoint between two floats: the closed form and
  // the clipping round within a few double ulps of it, so the closed form cannot decide alone and
  // must fall back; the results stay identical.
  Draw draw(5);
  ReceiverCapCounts counts;
  expect_identical("midpoints", 1500, kWindow, [&] {
    const float base = float(draw.uniform(0.1, 0.9));
    const double midpoint = 0.5 * (double(base) + double(std::nextafter(base, 1.0f)));
    LightSpacePoint centre = draw.around(kWindow, 0);
    centre.depth = midpoint;
    Triangle t = draw.around_point(centre, draw.log_uniform(5, 100));
    const double tilt = draw.integer(0, 2) == 0 ? 0.0 : draw.log_uniform(1e-18, 1e-12);
    for (LightSpacePoint* p : {&t.a, &t.b, &t.c}) p->depth = midpoint + tilt * (p->u - centre.u);
    return t;
  }, &counts);
  EXPECT_GT(counts.fallback, 0u) << "midpoint depths must exercise the fallback";
}

TEST(ReceiverSurfaceCaps, HouseTilesMatchTheClipping) {
  expect_scene_identical("fzk_haus/fzk_haus.obj", UpAxis::y, {}, 135, 45, 1024, 512);
}

TEST(ReceiverSurfaceCaps, TerrainTilesMatchTheClipping) {
  expect_scene_identical("terragen/RealisticTerrain.ter", UpAxis::z, {"*"}, 135, 30, 2048, 512);
}

// Given the tile's intervals, the pass skips triangles near no texel that takes a cap; every cap an
// exit takes is the same float, so the capped intervals are the same. The IFC house under
// `anywhere`: open walls and roofs (point intervals) beside a few closed solids.
TEST(ReceiverSurfaceCaps, GivenTheIntervalsEveryCapAnExitTakesIsUnchanged) {
  LoadOptions load;
  load.up = UpAxis::y;
  auto scene = load_scene(testing::shared_scene("fzk_haus/fzk_haus.obj"), load);
  ASSERT_TRUE(scene.ok()) << scene.error().message;
  const uint32_t resolution = 2048;
  auto frame = LightFrame::fit(*light_direction_from_sun(135, 45, UpAxis::y), scene->bounds, resolution);
  auto layout = TileLayout::make(resolution, 512);
  ASSERT_TRUE(frame.ok() && layout.ok());
  LightSpaceScene light_scene(*scene, *frame, *layout);
  auto device = EmbreeDevice::create();
  ASSERT_TRUE(device.ok());
  DualDepthOptions options;
  options.exit_margin = float(4.0 / resolution);
  options.cap_exits_at_receiver_surfaces = true;
  DualDepthRenderer renderer(*device, light_scene, options);
  ReceiverCapCounts all, given;
  size_t taking = 0, differing = 0;
  for (uint32_t y = 0; y < layout->tiles_per_side(); ++y)
    for (uint32_t x = 0; x < layout->tiles_per_side(); ++x) {
      auto intervals = renderer.render_centre({x, y});
      ASSERT_TRUE(intervals.ok());
      const std::vector<float> every = receiver_surface_caps(light_scene, {x, y}, &all);
      const std::vector<float> needed = receiver_surface_caps(light_scene, {x, y}, &given, {}, &*intervals);
      for (size_t i = 0; i < every.size(); ++i) {
        if (!takes_exit_cap(intervals->texels[i])) continue;
        ++taking;
        differing += std::bit_cast<uint32_t>(every[i]) != std::bit_cast<uint32_t>(needed[i]);
      }
      TileIntervals from_every = *intervals, from_needed = *intervals;
      apply_exit_caps(from_every, every, options.exit_margin);
      apply_exit_caps(from_needed, needed, options.exit_margin);
      for (size_t i = 0; i < every.size(); ++i) {
        ASSERT_EQ(from_every.texels[i].lower, from_needed.texels[i].lower);
        ASSERT_EQ(from_every.texels[i].upper, from_needed.texels[i].upper) << "tile " << x << "," << y << " texel " << i;
      }
    }
  EXPECT_EQ(differing, 0u);
  EXPECT_GT(taking, 1000u);  // the solids' exits: the caps that matter are there to compare
  EXPECT_EQ(all.triangles_skipped, 0u);
  EXPECT_GT(given.triangles_skipped, 0u);
  EXPECT_LT(given.interior + given.clipped, (all.interior + all.clipped) / 2);  // most of the pass saved
  std::printf("texels taking a cap %zu; triangles skipped %llu; texels rasterised %llu of %llu\n", taking,
              (unsigned long long)given.triangles_skipped, (unsigned long long)(given.interior + given.clipped),
              (unsigned long long)(all.interior + all.clipped));
}

TEST(ReceiverSurfaceCaps, BustTilesMatchTheClipping) {
  expect_scene_identical("nefertiti/nefertiti.obj", UpAxis::z, {}, 135, 45, 1024, 512);
}

}  // namespace
}  // namespace shadowtiles
