// The `surfaces` contract's entry rule (DualDepthOptions::entry_slack, docs/receiver-contracts.md,
// "The entry rule"), on an analytic scene under a sun straight above:
// - every receiver the truth lights and raw lights (query bias = the slack) is still lit by the
//   lowered bound, including beside a step whose lower side is visible inside the upper side's
//   texels (where the first-hit triangle does not cover the square, so the bound must stay);
// - texels inside one triangle, or inside two coplanar triangles across their shared edge, get
//   exactly the plane's deepest corner + tolerance - slack;
// - texels crossed by an outline edge (no triangle across it: the step) get the depth gap's bound:
//   the deepest point over the square of the surfaces within the exit margin of the first hit (both
//   sides of the step); the first hit itself stays in `lower` until apply_entry_rule (raw is encoded
//   from it);
// - on a real open scene (fzk_haus, 512^2), receivers sampled by area that Embree's ground truth
//   lights and raw lights stay lit.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>

#include "builder/dual_depth_renderer.hpp"
#include "builder/embree_device.hpp"
#include "builder/ground_truth.hpp"
#include "builder/light_space_scene.hpp"
#include "builder/receiver_sampler.hpp"
#include "builder/reference_entry_bounds.hpp"
#include "builder/scene.hpp"
#include "builder/scene_loader.hpp"
#include "builder/second_layer_rule.hpp"
#include "tests/testing_support.hpp"

namespace shadowtiles {
namespace {

using Triangles = std::vector<std::array<uint32_t, 3>>;

constexpr uint32_t kResolution = 64;
constexpr double kSlope = 0.02;  // world height per world unit along x: far under the slack per texel

// The upper surface: z = 2 + kSlope * x over x in [0, kStepX] (one quad, two triangles), a step down
// by `kStep` world units to a lower surface over x in [kStepX, 10] with the same slope; under both a second
// layer (half the step lower: the thin layer whose interval has zero width) and a floor at z = 0.
double upper_z(double x) { return 2 + kSlope * x; }
constexpr double kStep = 0.05;
constexpr double kStepX = 5.1;  // inside a texel (texels are 12.x / 64 wide, starting at x = -1)

void add_quad(Scene& scene, const std::string& name, double x0, double x1, double y0, double y1, double drop) {
  std::vector<Vec3> v{{x0, y0, upper_z(x0) - drop}, {x1, y0, upper_z(x1) - drop}, {x0, y1, upper_z(x0) - drop},
                      {x1, y1, upper_z(x1) - drop}};
  scene.add_mesh(name, v, Triangles{{0, 1, 3}, {0, 3, 2}});
}

// A floor, and a small lid high above a corner: the surfaces added between them lie well below the
// near plane, so their bounds are not clamped at depth 0, and they leave the map's bounds as they are.
Scene floor_under_a_lid() {
  Scene scene;
  scene.add_mesh("floor", {{-1, -1, 0}, {11, -1, 0}, {-1, 11, 0}, {11, 11, 0}}, Triangles{{0, 1, 3}, {0, 3, 2}});
  scene.add_mesh("lid", {{-1, -1, 10}, {-0.8, -1, 10}, {-1, -0.8, 10}}, Triangles{{0, 1, 2}});
  return scene;
}

Scene step_scene() {
  Scene scene = floor_under_a_lid();
  add_quad(scene, "upper", 0, kStepX, 0, 10, 0);
  add_quad(scene, "lower", kStepX, 10, 0, 10, kStep);
  add_quad(scene, "under_upper", 0.2, 4.8, 0.2, 9.8, kStep / 2);
  return scene;
}

struct Rendered {
  LightFrame frame;
  double slack = 0, tolerance = 0, gap = 0;  // normalised depth (gap: the exit margin)
  TileIntervals intervals;          // render(): first hits in lower, the rule's bounds beside
};

// The map as one tile of kResolution^2, or tile `tile` of a layout of `tile_size`^2 tiles (its
// intervals indexed by the tile's own texels).
Rendered render(const Scene& scene, uint32_t tile_size = kResolution, TileCoord tile = {0, 0}) {
  auto frame = LightFrame::fit({0, 0, -1}, scene.bounds, kResolution);
  EXPECT_TRUE(frame.ok());
  auto layout = TileLayout::make(kResolution, tile_size);
  LightSpaceScene light_scene(scene, *frame, *layout);
  auto device = EmbreeDevice::create();
  EXPECT_TRUE(device.ok());
  // The slack: two texels of depth, the build's default query bias; the step (0.05) is under it.
  const double slack = frame->depth_from_world(2 * frame->texel_size());
  DualDepthOptions options;
  options.exit_margin = float(2 * slack);
  options.cap_exits_at_receiver_surfaces = true;
  options.receivers = ReceiverContract::surfaces;
  options.coplanar_epsilon = float(second_layer::coplanar_epsilon(slack));
  options.entry_slack = float(slack);
  options.entry_tolerance = float(entry_tolerance_depth(*frame, scene.bounds));
  DualDepthRenderer renderer(*device, light_scene, options);
  auto intervals = renderer.render(tile);
  EXPECT_TRUE(intervals.ok());
  return {*frame, slack, options.entry_tolerance, options.exit_margin, std::move(*intervals)};
}

// The renderer runs the entry pass per band of rows; a tile with fewer rows than a band (8 here)
// must get its bounds all the same: every texel the one-tile map lowers, away from the small tiles'
// borders (where a square's cover may reach a triangle the small tile does not gather), is lowered
// to the same bound in its 8^2 tile.
TEST(EntryRule, TilesSmallerThanTheEntryPassBandGetTheSameBounds) {
  const Scene scene = step_scene();
  const Rendered whole = render(scene);
  constexpr uint32_t kSmall = 8;
  uint64_t compared = 0;
  for (uint32_t ty = 0; ty < kResolution / kSmall; ++ty)
    for (uint32_t tx = 0; tx < kResolution / kSmall; ++tx) {
      const Rendered part = render(scene, kSmall, {tx, ty});
      for (uint32_t v = 1; v + 1 < kSmall; ++v)
        for (uint32_t u = 1; u + 1 < kSmall; ++u) {
          const size_t global = size_t(ty * kSmall + v) * kResolution + tx * kSmall + u;
          const float first = whole.intervals.texels[global].lower, entry = whole.intervals.entry_lower[global];
          if (!(entry < first)) continue;
          ++compared;
          EXPECT_EQ(part.intervals.texels[size_t(v) * kSmall + u].lower, first) << tx << "," << ty << " " << u << "," << v;
          EXPECT_EQ(part.intervals.entry_lower[size_t(v) * kSmall + u], entry) << tx << "," << ty << " " << u << "," << v;
        }
    }
  EXPECT_GT(compared, uint64_t(kResolution) * kResolution / 4);  // most of the map is lowered
}

TEST(EntryRule, EveryLitReceiverRawLightsStaysLit) {
  const Scene scene = step_scene();
  Rendered r = render(scene);
  ASSERT_EQ(r.intervals.entry_lower.size(), r.intervals.texels.size());
  TileIntervals lowered = r.intervals;
  apply_entry_rule(lowered);
  EXPECT_TRUE(lowered.entry_lower.empty());
  // Receivers on the visible surfaces (nothing lies above them), on a grid finer than the texels.
  uint64_t raw_lit = 0, below_first_hit = 0;
  for (double x = 0.003; x < 10; x += 0.0173)
    for (double y = 0.003; y < 10; y += 0.0411) {
      const double z = x < kStepX ? upper_z(x) : upper_z(x) - kStep;
      const LightSpacePoint p = r.frame.to_light({x, y, z});
      const uint32_t u = uint32_t(p.u), v = uint32_t(p.v);
      const float threshold = float(p.depth - r.slack);  // the client's comparison, bias = the slack
      const DepthInterval& first = r.intervals.at(u, v);
      if (!(threshold <= first.lower)) continue;  // raw shadows it: nothing to keep
      ++raw_lit;
      ASSERT_LE(threshold, lowered.at(u, v).lower) << "x " << x << " y " << y << " texel " << u << "," << v;
      below_first_hit += lowered.at(u, v).lower < first.lower;
    }
  EXPECT_GT(raw_lit, 50000u);
  EXPECT_GT(below_first_hit, raw_lit / 2);  // the rule lowers most of them
}

TEST(EntryRule, InsideATriangleTheBoundIsItsDeepestCornerLessTheSlack) {
  const Scene scene = step_scene();
  Rendered r = render(scene);
  uint64_t inside = 0, on_edges = 0, on_diagonals = 0;
  for (uint32_t v = 0; v < kResolution; ++v)
    for (uint32_t u = 0; u < kResolution; ++u) {
      const DepthInterval& first = r.intervals.at(u, v);
      const float entry = r.intervals.entry_lower[size_t(v) * kResolution + u];
      if (first.lower >= 1.0f) {
        EXPECT_EQ(entry, first.lower);  // a miss stays a miss
        continue;
      }
      EXPECT_LE(entry, first.lower);
      // The texel's square in world x and y, grown by `grow` texels on each side.
      const Vec3 lo = r.frame.to_world({double(u), double(v), 0.5}), hi = r.frame.to_world({u + 1.0, v + 1.0, 0.5});
      if (std::max(lo[0], hi[0]) < 0.2 || std::min(lo[0], hi[0]) > 9.8 || std::max(lo[1], hi[1]) < 0.2 ||
          std::min(lo[1], hi[1]) > 9.8)
        continue;  // the floor's edges and border
      // Whether the grown square meets an outline edge of the upper and lower quads (x = 0, kStepX,
      // 10), or the diagonal each quad's two triangles share (from (x0q, 0) to (x1q, 10)).
      auto grown = [&](double grow) {
        const double g = grow * r.frame.texel_size();
        return std::array<double, 4>{std::min(lo[0], hi[0]) - g, std::max(lo[0], hi[0]) + g,
                                     std::min(lo[1], hi[1]) - g, std::max(lo[1], hi[1]) + g};
      };
      auto crosses_outline = [&](double grow) {
        const auto [x0, x1, y0, y1] = grown(grow);
        return (x0 <= kStepX && x1 >= kStepX) || (x0 <= 0 && x1 >= 0);
      };
      auto crosses_diagonal = [&](double grow) {
        const auto [x0, x1, y0, y1] = grown(grow);
        auto crosses = [&](double qx0, double qx1) {
          auto side = [&](double x, double y) { return (qx1 - qx0) * y - 10 * (x - qx0); };
          const double s00 = side(x0, y0), s01 = side(x0, y1), s10 = side(x1, y0), s11 = side(x1, y1);
          const bool mixed = std::min({s00, s01, s10, s11}) <= 0 && std::max({s00, s01, s10, s11}) >= 0;
          return mixed && x1 > qx0 && x0 < qx1;
        };
        return crosses(0, kStepX) || crosses(kStepX, 10);
      };
      if (crosses_outline(0)) {
        // No triangle across the step's edge covers the rest of the square, so the depth gap bounds
        // it: both quads come within the exit margin of the first hit there, and the deepest point
        // either has over the square is the lower quad's at the step (its plane clamped to its
        // vertices' range, which starts there; the reference clips to the same point).
        ++on_edges;
        const double deepest = r.frame.to_light({kStepX, std::min(lo[1], hi[1]), upper_z(kStepX) - kStep}).depth;
        const double expected = deepest + r.tolerance - r.slack;
        EXPECT_LT(entry, first.lower) << u << "," << v;
        EXPECT_NEAR(entry, expected, 4e-7) << u << "," << v;
        EXPECT_GE(double(entry), expected - 1e-7) << u << "," << v;
        continue;
      }
      if (crosses_outline(0.02)) continue;  // within the renderer's rounding margin (a hundredth of a texel)
      // Inside one triangle, or across the diagonal inside the pair of coplanar triangles: one plane.
      if (crosses_diagonal(0)) ++on_diagonals;
      const double x0 = std::min(lo[0], hi[0]), y0 = std::min(lo[1], hi[1]);
      ++inside;
      // The plane's deepest corner over the square: the sun is straight above and z grows with x,
      // so it is the lowest point, at the square's smallest x.
      const double deepest = r.frame.to_light({x0, y0, x0 < kStepX ? upper_z(x0) : upper_z(x0) - kStep}).depth;
      const double expected = deepest + r.tolerance - r.slack;
      EXPECT_NEAR(entry, expected, 4e-7) << u << "," << v;
      EXPECT_GE(double(entry), expected - 1e-7) << u << "," << v;  // rounded up, never below
    }
  EXPECT_GT(on_diagonals, 100u);
  EXPECT_GT(inside, 1500u);
  EXPECT_GT(on_edges, 40u);  // the step's column
}

// Two triangles on the two sides of a shared edge whose union is not convex at its end B: a square
// can have every corner inside one of them while a strip of it (where its side crosses the edge's
// line beyond B) lies in neither, and what lies below shows through there. `below`: how much deeper
// than the kite (in query slacks) a plate under it lies; none: only the floor, far below.
struct KiteBounds {
  Rendered rendered;
  std::vector<float> reference;
};
KiteBounds kite_over(std::optional<double> below) {
  Scene scene = floor_under_a_lid();
  const auto frame = LightFrame::fit({0, 0, -1}, scene.bounds, kResolution);
  EXPECT_TRUE(frame.ok());
  // In texels from the corner (32, 32), at height 2: T = (A, B, C) and N = (A, B, D) share A-B.
  const double depth = frame->to_light({5, 5, 2}).depth;
  auto at = [&](double x, double y, double d) { return frame->to_world({32 + x, 32 + y, d}); };
  scene.add_mesh("kite", {at(-30, -30, depth), at(0.8, 0.9, depth), at(-2, 5, depth), at(30, 20, depth)},
                 Triangles{{0, 1, 2}, {0, 3, 1}});
  if (below) {
    const double d = depth + *below * frame->depth_from_world(2 * frame->texel_size());  // render()'s slack
    scene.add_mesh("plate", {at(-8, -8, d), at(8, -8, d), at(-8, 8, d), at(8, 8, d)}, Triangles{{0, 1, 3}, {0, 3, 2}});
  }
  KiteBounds k{render(scene), {}};
  EXPECT_NEAR(k.rendered.frame.texel_size(), frame->texel_size(), 1e-12);  // the kite leaves the bounds as they were
  LightSpaceScene light_scene(scene, k.rendered.frame, *TileLayout::make(kResolution, kResolution));
  const Rendered& r = k.rendered;
  k.reference = reference_entry_bounds(light_scene, {0, 0}, r.intervals, r.slack, r.tolerance, r.gap);
  return k;
}

void expect_lowered(const KiteBounds& k, uint32_t u, uint32_t v, bool lowered) {
  const size_t i = size_t(v) * kResolution + u;
  const float first = k.rendered.intervals.texels[i].lower;
  ASSERT_LT(first, 1.0f) << u << "," << v;
  EXPECT_EQ(k.rendered.intervals.entry_lower[i] < first, lowered) << "renderer, texel " << u << "," << v;
  EXPECT_EQ(k.reference[i] < first, lowered) << "reference, texel " << u << "," << v;
  EXPECT_LE(k.reference[i], k.rendered.intervals.entry_lower[i]) << "texel " << u << "," << v;
}

// A plate 1.5 slacks under the kite (within the exit margin of 2 slacks, deeper than the slack): a
// receiver on it beyond B is lit by the truth and may be lit by raw, so neither the renderer nor
// verify's reference may lower the texel over the gap, by a cover or by the depth gap; a square
// inside one triangle, and one straddling the edge away from B, are covered and lowered by both.
TEST(EntryRule, ASquareOverTheGapBeyondASharedEdgeKeepsItsFirstHit) {
  const KiteBounds k = kite_over(1.5);
  expect_lowered(k, 32, 32, false);  // over the gap beyond B
  expect_lowered(k, 36, 32, true);   // inside N
  expect_lowered(k, 17, 17, true);   // across A-B, away from its ends
}

// With only the floor under the gap (far deeper than the exit margin: no receiver there is lit by
// raw), the depth gap lowers the texel over the gap, in the renderer and the reference alike, to the
// kite's plane over the square; a plate half a slack under the kite (within the slack) lowers it
// too, by less: the plate's receivers beyond B stay lit.
TEST(EntryRule, ASquareOverADeepGapIsLoweredByTheDepthGap) {
  const KiteBounds deep = kite_over(std::nullopt);
  expect_lowered(deep, 32, 32, true);
  const KiteBounds near = kite_over(0.5);
  expect_lowered(near, 32, 32, true);
  const size_t i = size_t(32) * kResolution + 32;
  EXPECT_GT(near.rendered.intervals.entry_lower[i], deep.rendered.intervals.entry_lower[i]);
  // The plate lies flat half a slack deeper: the bound is its depth less half a slack at most.
  const Rendered& r = near.rendered;
  EXPECT_NEAR(r.intervals.entry_lower[i], r.intervals.texels[i].lower - 0.5 * r.slack + r.tolerance, 1e-6);
}

// A square cut up by hundreds of small triangles a little shallower than a large one under them all:
// the large one covers the square by itself, so both the renderer (its first hit) and verify's
// reference lower the texel. In depth order the small ones come first and split the square's
// remainder into ever more pieces (a dense tile of honolulu_airport at 4096^2 had such squares); the
// reference must still find the cover (until 2026-12-06 it gave up past 256 pieces, and verify
// reported 552 texels of that scene outside their intervals).
TEST(EntryRule, TheReferenceFindsTheCoverOfASquareCutUpByManySmallTriangles) {
  Scene scene = floor_under_a_lid();
  const auto frame = LightFrame::fit({0, 0, -1}, scene.bounds, kResolution);
  ASSERT_TRUE(frame.ok());
  const double depth = frame->to_light({5, 5, 2}).depth, above = frame->to_light({5, 5, 2.001}).depth;
  auto at = [&](double u, double v, double d) { return frame->to_world({u, v, d}); };
  scene.add_mesh("large", {at(30, 30, depth), at(60, 30, depth), at(30, 60, depth)}, Triangles{{0, 1, 2}});
  // 18 x 18 small triangles over texel (40, 40), none at its centre.
  std::vector<Vec3> vertices;
  Triangles small;
  for (int i = 0; i < 18; ++i)
    for (int j = 0; j < 18; ++j) {
      if (std::abs(i - 9) <= 1 && std::abs(j - 9) <= 1) continue;
      const double u = 40 + (i + 0.3) / 18, v = 40 + (j + 0.3) / 18, side = 0.6 / 18;
      const uint32_t base = uint32_t(vertices.size());
      vertices.insert(vertices.end(), {at(u, v, above), at(u + side, v, above), at(u, v + side, above)});
      small.push_back({base, base + 1, base + 2});
    }
  scene.add_mesh("small", vertices, small);
  Rendered r = render(scene);
  ASSERT_NEAR(r.frame.texel_size(), frame->texel_size(), 1e-12);  // the bounds are the floor's and lid's
  LightSpaceScene light_scene(scene, r.frame, *TileLayout::make(kResolution, kResolution));
  const std::vector<float> reference = reference_entry_bounds(light_scene, {0, 0}, r.intervals, r.slack, r.tolerance, r.gap);
  const size_t i = size_t(40) * kResolution + 40;
  const float first = r.intervals.texels[i].lower;
  ASSERT_NEAR(first, depth, 1e-6);  // the centre ray hits the large triangle
  EXPECT_LT(r.intervals.entry_lower[i], first);
  EXPECT_LT(reference[i], first);
  EXPECT_LE(reference[i], r.intervals.entry_lower[i]);  // the reference is never above the renderer's bound
}

// A square crossed by two edges of its first-hit triangle T near their shared vertex V (V outside
// the square): it is covered by T and the two triangles across those edges, so it is lowered, and
// its bound must reach the deepest of the three over the square. One triangle across slopes down
// away from V (the left one, then the right one), so the bound is set by it: a cover that left it
// out would lower the texel below verify's reference, which clips every triangle to the square.
TEST(EntryRule, ASquareCrossingTwoEdgesNearTheirVertexIsBoundedByBothTrianglesAcross) {
  for (const bool left_deep : {true, false}) {
    SCOPED_TRACE(left_deep ? "the left triangle across slopes down" : "the right triangle across slopes down");
    Scene scene = floor_under_a_lid();
    const auto frame = LightFrame::fit({0, 0, -1}, scene.bounds, kResolution);
    ASSERT_TRUE(frame.ok());
    const double depth = frame->to_light({5, 5, 2}).depth, deeper = frame->to_light({5, 5, 0.5}).depth;
    auto at = [&](double u, double v, double d) { return frame->to_world({u, v, d}); };
    // Texel (32, 32) spans [32, 33]^2; T = (V, P, Q) is 0.12 texels wide across its centre row, and
    // the square lies inside the two triangles across's other edges (V's spokes to X and Y run wide).
    scene.add_mesh("fan",
                   {at(32.5, 33.3, depth) /* V */, at(31.5, 20, depth) /* P */, at(33.5, 20, depth) /* Q */,
                    at(25, 34, left_deep ? deeper : depth) /* X */, at(40, 34, left_deep ? depth : deeper) /* Y */},
                   Triangles{{0, 1, 2}, {0, 3, 1}, {0, 2, 4}});
    Rendered r = render(scene);
    ASSERT_NEAR(r.frame.texel_size(), frame->texel_size(), 1e-12);
    LightSpaceScene light_scene(scene, r.frame, *TileLayout::make(kResolution, kResolution));
    const std::vector<float> reference =
        reference_entry_bounds(light_scene, {0, 0}, r.intervals, r.slack, r.tolerance, r.gap);
    const size_t i = size_t(32) * kResolution + 32;
    const float first = r.intervals.texels[i].lower;
    ASSERT_NEAR(first, depth, 1e-6);  // the centre ray hits T
    const float entry = r.intervals.entry_lower[i];
    EXPECT_LT(entry, first);
    EXPECT_LE(reference[i], entry);
    // The slope counts: over the flat T and the flat triangle across alone the bound would be the
    // first hit + tolerance - slack.
    EXPECT_GT(double(reference[i]), double(first) + r.tolerance - r.slack + 0.1 * r.slack);
  }
}

// fzk_haus at 512^2 under `surfaces` with the rule on at the build's default bias (2 texels), the
// renderer's intervals (with its bounds beside) and verify's reference bounds from the centre intervals.
struct RealScene {
  Scene scene;
  Vec3 light{};
  std::unique_ptr<LightFrame> frame;
  std::unique_ptr<LightSpaceScene> light_scene;
  double bias = 0;
  TileIntervals rendered;
  std::vector<float> reference;
};

RealScene real_scene() {
  RealScene r;
  LoadOptions load;
  load.up = UpAxis::y;
  auto scene = load_scene(testing::shared_scene("fzk_haus/fzk_haus.obj"), load);
  EXPECT_TRUE(scene.ok()) << scene.error().message;
  r.scene = std::move(*scene);
  r.light = *light_direction_from_sun(135, 45, UpAxis::y);
  constexpr uint32_t kMap = 512;
  r.frame = std::make_unique<LightFrame>(*LightFrame::fit(r.light, r.scene.bounds, kMap));
  r.light_scene = std::make_unique<LightSpaceScene>(r.scene, *r.frame, *TileLayout::make(kMap, kMap));
  auto device = EmbreeDevice::create();
  EXPECT_TRUE(device.ok());
  r.bias = r.frame->depth_from_world(2 * r.frame->texel_size());
  DualDepthOptions options;
  options.exit_margin = float(r.frame->depth_from_world(4 * r.frame->texel_size()));
  options.cap_exits_at_receiver_surfaces = true;
  options.receivers = ReceiverContract::surfaces;
  options.coplanar_epsilon = float(second_layer::coplanar_epsilon(r.bias));
  options.entry_slack = float(r.bias);
  options.entry_tolerance = float(entry_tolerance_depth(*r.frame, r.scene.bounds));
  DualDepthRenderer renderer(*device, *r.light_scene, options);
  auto rendered = renderer.render({0, 0});
  auto centre = renderer.render_centre({0, 0});
  EXPECT_TRUE(rendered.ok() && centre.ok());
  r.rendered = std::move(*rendered);
  r.reference = reference_entry_bounds(*r.light_scene, {0, 0}, *centre, options.entry_slack, options.entry_tolerance,
                                       options.exit_margin);
  return r;
}

TEST(EntryRule, OnARealOpenSceneGroundTruthLitReceiversRawLightsStayLit) {
  RealScene r = real_scene();
  const TileIntervals& first = r.rendered;
  TileIntervals lowered = first;
  apply_entry_rule(lowered);
  auto device = EmbreeDevice::create();
  ASSERT_TRUE(device.ok());
  GroundTruth truth(*device, r.scene, r.light);
  uint64_t kept = 0, lowered_texels = 0;
  for (const Receiver& receiver : sample_receivers(r.scene, 20000, 11)) {
    const LightSpacePoint p = r.frame->to_light(receiver.position);
    if (!(p.u >= 0 && p.u < first.size && p.v >= 0 && p.v < first.size)) continue;
    const uint32_t u = uint32_t(p.u), v = uint32_t(p.v);
    const float threshold = float(std::min(p.depth, 1.0) - r.bias);  // the client's comparison
    if (!(threshold <= first.at(u, v).lower) || !truth.lit(receiver.position)) continue;
    ++kept;
    lowered_texels += lowered.at(u, v).lower < first.at(u, v).lower;
    EXPECT_LE(threshold, lowered.at(u, v).lower) << "receiver at texel " << u << "," << v;
    // verify's reference bound is sound too.
    EXPECT_LE(threshold, r.reference[size_t(v) * first.size + u]) << "reference, texel " << u << "," << v;
  }
  EXPECT_GT(kept, 2000u);
  EXPECT_GT(lowered_texels, kept / 2);
}

// The reference (the shallowest set of any triangles covering the exact square) is never above the
// renderer's bound (a cover grown from the first hit's triangle across shared edges, square grown for
// rounding), so verify accepts what the build stores; it is lower where other triangles cover the
// square more tightly.
TEST(EntryRule, TheReferenceBoundIsNeverAboveTheRenderers) {
  RealScene r = real_scene();
  uint64_t hits = 0, close = 0, tighter = 0;
  for (size_t i = 0; i < r.reference.size(); ++i) {
    const float first = r.rendered.texels[i].lower, renderer = r.rendered.entry_lower[i], reference = r.reference[i];
    ASSERT_LE(reference, first) << i;
    ASSERT_LE(reference, renderer) << "texel " << i % r.rendered.size << "," << i / r.rendered.size;
    if (first >= 1.0f) continue;
    ++hits;
    // The renderer's bound is one float step above its rounding; the same plane gives the same bound.
    float within = reference;
    for (int step = 0; step < 3; ++step) within = std::nextafter(within, 2.0f);
    close += renderer <= within;
    tighter += renderer > within;
  }
  EXPECT_GT(close, hits / 2);
  std::printf("fzk_haus 512^2: %llu hit texels, reference within 3 float steps of the renderer's bound on %llu, "
              "lower on %llu\n",
              (unsigned long long)hits, (unsigned long long)close, (unsigned long long)tighter);
}

}  // namespace
}  // namespace shadowtiles
