// The `surfaces` contract's second-layer caps on analytic scenes (docs/receiver-contracts.md), built
// by the build's fast pass (DualDepthRenderer::render, second_layer_caps) and by verify's brute-force
// reference (apply_reference_caps on the centre intervals):
// - near cover: a receiver less than the bias under its occluder on a steep slope, deeper than the
//   centre's first hit + bias somewhere in the texel, must stay shadowed wherever raw shadows it
//   (STABILITY.md's bunny finding; without near cover the interval reached the floor and lit it);
// - exact coplanar duplicates (IFC double faces) on the same slope keep their interval's width.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <random>

#include "builder/dual_depth_renderer.hpp"
#include "builder/embree_device.hpp"
#include "builder/light_space_scene.hpp"
#include "builder/reference_caps.hpp"
#include "builder/scene.hpp"
#include "builder/second_layer_caps.hpp"
#include "builder/second_layer_rule.hpp"

namespace shadowtiles {
namespace {

using Triangles = std::vector<std::array<uint32_t, 3>>;

constexpr uint32_t kResolution = 64;
constexpr double kBiasWorld = 0.016;
constexpr double kSlope = 0.6;        // world height per world unit along x: ~5 biases per texel
constexpr double kUnderBy = 0.008;    // the receiver slope lies half a bias under its occluder

double slope_z(double x) { return 2 + kSlope * x; }

// A quad z = slope_z(x) - drop over [x0, x1] x [y0, y1], one-sided (winding flipped by `flip`).
void add_slope(Scene& scene, const std::string& name, double x0, double x1, double y0, double y1, double drop,
               bool flip = false) {
  std::vector<Vec3> v{{x0, y0, slope_z(x0) - drop}, {x1, y0, slope_z(x1) - drop}, {x0, y1, slope_z(x0) - drop},
                      {x1, y1, slope_z(x1) - drop}};
  Triangles t{{0, 1, 3}, {0, 3, 2}};
  if (flip)
    for (auto& tri : t) std::swap(tri[1], tri[2]);
  scene.add_mesh(name, v, t);
}

// Floor at z = 0; y in [0, 4]: an open slope with a second one half a bias under it; y in [6, 10]:
// the same slope as a back-to-back double face (exact duplicate vertices).
Scene near_cover_scene() {
  Scene scene;
  scene.add_mesh("floor", {{-1, -1, 0}, {11, -1, 0}, {-1, 11, 0}, {11, 11, 0}}, Triangles{{0, 1, 3}, {0, 3, 2}});
  add_slope(scene, "occluder", 0, 10, 0, 4, 0);
  add_slope(scene, "receiver", 0.5, 9.5, 0.5, 3.5, kUnderBy);
  add_slope(scene, "double_face_front", 0, 10, 6, 10, 0);
  add_slope(scene, "double_face_back", 0, 10, 6, 10, 0, true);
  return scene;
}

struct Built {
  LightFrame frame;
  DualDepthOptions options;
  TileIntervals fast;       // render(): centre intervals capped by second_layer_caps
  TileIntervals reference;  // render_centre() capped by apply_reference_caps
};

// The renderer's options under `surfaces` with caps, at the tests' bias (exit margin 2 biases).
DualDepthOptions surfaces_options(const LightFrame& frame) {
  const double bias = frame.depth_from_world(kBiasWorld);
  DualDepthOptions options;
  options.exit_margin = float(2 * bias);
  options.cap_exits_at_receiver_surfaces = true;
  options.receivers = ReceiverContract::surfaces;
  options.coplanar_epsilon = float(second_layer::coplanar_epsilon(bias));
  return options;
}

Built build(const Scene& scene) {
  auto frame = LightFrame::fit({0, 0, -1}, scene.bounds, kResolution);
  EXPECT_TRUE(frame.ok());
  auto layout = TileLayout::make(kResolution, kResolution);
  LightSpaceScene light_scene(scene, *frame, *layout);
  auto device = EmbreeDevice::create();
  EXPECT_TRUE(device.ok());
  const double bias = frame->depth_from_world(kBiasWorld);
  const DualDepthOptions options = surfaces_options(*frame);
  DualDepthRenderer renderer(*device, light_scene, options);
  auto fast = renderer.render({0, 0});
  auto centre = renderer.render_centre({0, 0});
  EXPECT_TRUE(fast.ok() && centre.ok());
  apply_reference_caps(light_scene, {0, 0}, ReceiverContract::surfaces, second_layer::coplanar_epsilon(bias),
                       options.exit_margin, *centre);
  return {*frame, options, std::move(*fast), std::move(*centre)};
}

struct Leaks {
  uint64_t raw_shadowed = 0;  // receiver points raw shadows (the truth shadows them all)
  uint64_t lit_by_upper = 0;  // ... that the interval's upper value lights
};

// Receivers on the under slope on a fine grid, queried as the client does: lit iff
// float(depth - bias) <= value.
Leaks under_slope_leaks(const Built& built, const TileIntervals& intervals) {
  Leaks leaks;
  const double bias = built.frame.depth_from_world(kBiasWorld);
  for (double x = 0.52; x < 9.48; x += 0.013)
    for (double y = 0.52; y < 3.48; y += 0.029) {
      const LightSpacePoint p = built.frame.to_light({x, y, slope_z(x) - kUnderBy});
      const DepthInterval& texel = intervals.at(uint32_t(p.u), uint32_t(p.v));
      const float threshold = float(p.depth - bias);
      if (!(threshold > texel.lower)) continue;
      ++leaks.raw_shadowed;
      leaks.lit_by_upper += threshold <= texel.upper;
    }
  return leaks;
}

TEST(SecondLayerCaps, ReceiverJustUnderItsOccluderOnASlopeStaysShadowedWhereRawShadowsIt) {
  const Built built = build(near_cover_scene());
  for (const auto* intervals : {&built.fast, &built.reference}) {
    const Leaks leaks = under_slope_leaks(built, *intervals);
    const char* which = intervals == &built.fast ? "build (second_layer_caps)" : "verify (reference_caps)";
    EXPECT_GT(leaks.raw_shadowed, 1000u) << which << ": the scene must put receivers deeper than lower + bias";
    EXPECT_EQ(leaks.lit_by_upper, 0u) << which << ": of " << leaks.raw_shadowed << " raw-shadowed receivers";
  }
}

TEST(SecondLayerCaps, ExactDoubleFacesOnASlopeKeepTheirWidth) {
  const Built built = build(near_cover_scene());
  const float floor_depth = float(built.frame.to_light({5, 8, 0}).depth);
  for (const auto* intervals : {&built.fast, &built.reference}) {
    uint64_t texels = 0, wide = 0;
    for (double x = 0.5; x < 9.5; x += 0.15625)
      for (double y = 6.5; y < 9.5; y += 0.15625) {
        const LightSpacePoint p = built.frame.to_light({x, y, slope_z(x)});
        const DepthInterval& texel = intervals->at(uint32_t(p.u), uint32_t(p.v));
        ++texels;
        // Capped by the floor behind the double face, not by the duplicate itself.
        wide += texel.upper - texel.lower > 0.5f * (floor_depth - texel.lower);
      }
    EXPECT_GT(texels, 500u);
    EXPECT_EQ(wide, texels) << (intervals == &built.fast ? "build" : "verify");
  }
}

TEST(SecondLayerCaps, BuildCapsAreNeverAboveTheReference) {
  const Built built = build(near_cover_scene());
  uint64_t above = 0;
  for (size_t i = 0; i < built.fast.texels.size(); ++i) {
    const float fast = built.fast.texels[i].upper, reference = built.reference.texels[i].upper;
    above += fast > std::nextafter(std::nextafter(reference, 2.0f), 2.0f);  // verify's 2-float-step slack
  }
  EXPECT_EQ(above, 0u);
}

// A sliver with a corner of ~5e-8 rad over the floor: its edges widened by 2^-20 texels meet ~40
// texels past that corner. The floor under the sliver is its second layer (caps along the sliver's
// row); the floor beyond the corner lies under nothing and keeps its exit, as the reference says.
TEST(SecondLayerCaps, ASharpSliverCapsOnlyWhereItLies) {
  Scene scene;
  scene.add_mesh("floor", {{-1, -1, 0}, {11, -1, 0}, {-1, 11, 0}, {11, 11, 0}}, Triangles{{0, 1, 3}, {0, 3, 2}});
  scene.add_mesh("lid", {{-1, -1, 4}, {-0.8, -1, 4}, {-1, -0.8, 4}}, Triangles{{0, 1, 2}});
  const auto frame = LightFrame::fit({0, 0, -1}, scene.bounds, kResolution);
  ASSERT_TRUE(frame.ok());
  const double depth = frame->to_light({5, 5, 2}).depth;
  auto at = [&](double u, double v) { return frame->to_world({u, v, depth}); };
  scene.add_mesh("sliver", {at(5, 30.5), at(25, 30.5), at(5, 30.5 + 1e-6)}, Triangles{{0, 1, 2}});
  const Built built = build(scene);
  ASSERT_NEAR(built.frame.texel_size(), frame->texel_size(), 1e-12);
  uint64_t under = 0, beyond = 0, beyond_capped = 0;
  for (uint32_t u = 6; u < kResolution; ++u) {
    const DepthInterval& fast = built.fast.at(u, 30);
    const DepthInterval& reference = built.reference.at(u, 30);
    ASSERT_LE(fast.upper, std::nextafter(std::nextafter(reference.upper, 2.0f), 2.0f)) << u;
    if (u < 24) under += reference.upper < 1.0f;  // the floor under the sliver: capped
    if (u < 27) continue;
    ++beyond;
    beyond_capped += fast.upper != reference.upper;
  }
  EXPECT_GT(under, 15u);
  EXPECT_GT(beyond, 30u);
  EXPECT_EQ(beyond_capped, 0u);
}

// Random triangle soups: sizes from a hundredth of a texel to the whole map, slivers, steep walls,
// stacked and crossing faces. The fast pass drops pairs before clipping (separating edges, planes
// nowhere behind over the pair's box); a pair dropped wrongly would leave a cap above the reference.
Scene random_soup(uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0, 1);
  Scene scene;
  scene.add_mesh("floor", {{-1, -1, 0}, {11, -1, 0}, {-1, 11, 0}, {11, 11, 0}}, Triangles{{0, 1, 3}, {0, 3, 2}});
  std::vector<Vec3> vertices;
  Triangles triangles;
  for (uint32_t k = 0; k < 400; ++k) {
    const double size = 0.002 * std::pow(5000.0, unit(rng));  // 1/100 texel .. the map (64 texels on 10)
    const Vec3 centre{10 * unit(rng), 10 * unit(rng), 0.2 + 4 * unit(rng)};
    const double steep = unit(rng) < 0.2 ? 3.0 : 0.5;  // a fifth are walls, nearly along the light
    auto corner = [&] {
      return Vec3{centre[0] + size * (unit(rng) - 0.5), centre[1] + size * (unit(rng) - 0.5),
                  centre[2] + steep * size * (unit(rng) - 0.5)};
    };
    Vec3 a = corner(), b = corner(), c = corner();
    if (unit(rng) < 0.2) {  // a sliver: c just off the segment a-b
      const double t = unit(rng), off = 1e-4 * unit(rng);
      c = {a[0] + t * (b[0] - a[0]) + off, a[1] + t * (b[1] - a[1]) - off,
           a[2] + t * (b[2] - a[2]) + size * (unit(rng) - 0.5)};
    }
    const uint32_t base = uint32_t(vertices.size());
    vertices.insert(vertices.end(), {a, b, c});
    triangles.push_back({base, base + 1, base + 2});
  }
  scene.add_mesh("soup", vertices, triangles);
  return scene;
}

struct AgainstReference {
  uint64_t above = 0;   // texels whose build upper lies above the reference's by more than verify's slack
  uint64_t capped = 0;  // texels the reference caps below their exit (what the comparison exercises)
};

AgainstReference compare_with_reference(const Built& built) {
  AgainstReference result;
  for (size_t i = 0; i < built.fast.texels.size(); ++i) {
    const float fast = built.fast.texels[i].upper, reference = built.reference.texels[i].upper;
    // (texels the map's rays miss have upper +inf in both)
    result.above += fast > reference && fast > std::nextafter(std::nextafter(reference, 2.0f), 2.0f);
    result.capped += reference < 1.0f && reference > built.reference.texels[i].lower;
  }
  return result;
}

TEST(SecondLayerCaps, RandomSoupsBuildCapsAreNeverAboveTheReference) {
  for (uint32_t seed : {1u, 2u, 3u, 4u}) {
    const AgainstReference result = compare_with_reference(build(random_soup(seed)));
    EXPECT_EQ(result.above, 0u) << "seed " << seed;
    EXPECT_GT(result.capped, 100u) << "seed " << seed << ": the soup should leave exits to cap";
  }
}

// Crumpled meshes: a grid of shared vertices, jittered in x and y by up to a cell so that faces fold
// over their neighbours, with random heights. Pairs that share an edge or a vertex are what the fast
// pass's edge gap test drops before clipping (the part of one a widened edge of the other keeps is a
// sliver along the shared edge or vertex); a fold must not be dropped with them.
// Two triangles per cell of a side x side grid of vertices in row-major order.
Triangles grid_triangles(uint32_t side) {
  Triangles triangles;
  for (uint32_t j = 0; j + 1 < side; ++j)
    for (uint32_t i = 0; i + 1 < side; ++i) {
      const uint32_t a = j * side + i, b = a + 1, c = a + side, d = c + 1;
      triangles.push_back({a, b, d});
      triangles.push_back({a, d, c});
    }
  return triangles;
}

Scene crumpled_mesh(uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0, 1);
  Scene scene;
  scene.add_mesh("floor", {{-1, -1, 0}, {11, -1, 0}, {-1, 11, 0}, {11, 11, 0}}, Triangles{{0, 1, 3}, {0, 3, 2}});
  constexpr uint32_t kSide = 25;
  const double cell = 10.0 / (kSide - 1);
  std::vector<Vec3> vertices;
  for (uint32_t j = 0; j < kSide; ++j)
    for (uint32_t i = 0; i < kSide; ++i)
      vertices.push_back({i * cell + cell * (unit(rng) - 0.5) * 1.6, j * cell + cell * (unit(rng) - 0.5) * 1.6,
                          1 + 2 * unit(rng)});
  scene.add_mesh("crumpled", vertices, grid_triangles(kSide));
  return scene;
}

TEST(SecondLayerCaps, CrumpledMeshesBuildCapsAreNeverAboveTheReference) {
  for (uint32_t seed : {1u, 2u, 3u}) {
    const AgainstReference result = compare_with_reference(build(crumpled_mesh(seed)));
    EXPECT_EQ(result.above, 0u) << "seed " << seed;
    EXPECT_GT(result.capped, 100u) << "seed " << seed << ": the folds should leave exits to cap";
  }
}

// The texel-by-texel test before the clips (second_layer_caps' `texel_tests`) skips only regions
// that cannot change an interval: with and without it, every capped interval is the same bit for
// bit, on a 128^2 map in four 64^2 tiles (three of them away from the origin), while it does skip
// pairs. Taking a quarter texel of slope off the bound changes some texel's upper here; raising the
// roof's bound behind epsilon by up to two biases does not, since near cover caps those texels at
// the same depth (docs/build-time.md, session 37).
// A flat roof with a gently tilted plane under it that comes within the coplanar epsilon of it
// halfway: along that line the region behind by epsilon is shallowest at roof + epsilon, where the
// roof's plane, not the tilted one's, bounds it. Both are grids of small quads (boxes of a few
// texels), since larger boxes skip the texel test.
void add_grid(Scene& scene, const std::string& name, double z0, double dz_dx) {
  constexpr uint32_t kSide = 41;
  std::vector<Vec3> vertices;
  for (uint32_t j = 0; j < kSide; ++j)
    for (uint32_t i = 0; i < kSide; ++i) vertices.push_back({i * 0.25, j * 0.25, z0 + dz_dx * i * 0.25});
  scene.add_mesh(name, vertices, grid_triangles(kSide));
}

Scene plane_nearing_a_roof() {
  Scene scene;
  scene.add_mesh("floor", {{-1, -1, 0}, {11, -1, 0}, {-1, 11, 0}, {11, 11, 0}}, Triangles{{0, 1, 3}, {0, 3, 2}});
  add_grid(scene, "roof", 3.0, 0);
  add_grid(scene, "tilted", 2.96, 0.004);
  return scene;
}

TEST(SecondLayerCaps, TexelTestsBeforeTheClipsChangeNoInterval) {
  constexpr uint32_t kMap = 128, kTile = 64;
  uint64_t pairs_with = 0, pairs_without = 0, exits = 0;
  std::vector<Scene> scenes{near_cover_scene(), plane_nearing_a_roof(), random_soup(1), random_soup(2),
                            crumpled_mesh(1), crumpled_mesh(2)};
  for (size_t s = 0; s < scenes.size(); ++s) {
    auto frame = LightFrame::fit({0, 0, -1}, scenes[s].bounds, kMap);
    ASSERT_TRUE(frame.ok());
    auto layout = TileLayout::make(kMap, kTile);
    ASSERT_TRUE(layout.ok());
    LightSpaceScene light_scene(scenes[s], *frame, *layout);
    auto device = EmbreeDevice::create();
    ASSERT_TRUE(device.ok());
    const DualDepthOptions options = surfaces_options(*frame);
    DualDepthRenderer renderer(*device, light_scene, options);
    for (uint32_t ty = 0; ty < kMap / kTile; ++ty)
      for (uint32_t tx = 0; tx < kMap / kTile; ++tx) {
        auto centre = renderer.render_centre({tx, ty});
        ASSERT_TRUE(centre.ok());
        TileIntervals with = *centre, without = *centre;
        SecondLayerCapCounts counts_with, counts_without;
        const auto caps_with = second_layer_caps(light_scene, {tx, ty}, options.coplanar_epsilon, *centre,
                                                 options.exit_margin, &counts_with);
        const auto caps_without = second_layer_caps(light_scene, {tx, ty}, options.coplanar_epsilon, *centre,
                                                    options.exit_margin, &counts_without, {}, nullptr, false);
        apply_exit_caps(with, caps_with, options.exit_margin);
        apply_exit_caps(without, caps_without, options.exit_margin);
        uint64_t differ = 0;
        for (size_t i = 0; i < with.texels.size(); ++i) {
          differ += std::bit_cast<uint32_t>(with.texels[i].upper) != std::bit_cast<uint32_t>(without.texels[i].upper) ||
                    std::bit_cast<uint32_t>(with.texels[i].lower) != std::bit_cast<uint32_t>(without.texels[i].lower);
          exits += without.texels[i].upper > without.texels[i].lower && without.texels[i].lower < 1.0f;
        }
        EXPECT_EQ(differ, 0u) << "scene " << s << ", tile " << tx << "," << ty;
        pairs_with += counts_with.pairs_tested, pairs_without += counts_without.pairs_tested;
      }
  }
  EXPECT_GT(exits, 10000u);  // the scenes leave intervals to cap
  EXPECT_LT(pairs_with, pairs_without) << "the test should send fewer pairs to the clips";
}

}  // namespace
}  // namespace shadowtiles
