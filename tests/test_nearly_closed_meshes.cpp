// Nearly closed solids (builder/nearly_closed_meshes.hpp, docs/receiver-contracts.md): a sphere with one
// triangle removed is accepted and exits as the closed sphere does; a large hole is refused; a ray
// through a hole facing the light stays conservative; a ray leaving through a hole exits at the patch;
// the verifier's brute-force caps agree with the build's on the patched scenes; a whole build verifies.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <numbers>

#include "builder/build_job.hpp"
#include "builder/dual_depth_renderer.hpp"
#include "builder/embree_device.hpp"
#include "builder/light_space_scene.hpp"
#include "builder/nearly_closed_meshes.hpp"
#include "builder/reference_caps.hpp"
#include "builder/scene.hpp"
#include "tests/testing_support.hpp"
#include "tests/verified_build.hpp"

namespace shadowtiles {
namespace {

using Triangles = std::vector<std::array<uint32_t, 3>>;

struct Mesh {
  std::vector<Vec3> vertices;
  Triangles triangles;
};

// UV sphere of radius r around c, counter-clockwise seen from outside.
Mesh sphere(Vec3 c, double r, int slices, int stacks) {
  Mesh m;
  for (int j = 0; j <= stacks; ++j) {
    const double theta = std::numbers::pi * j / stacks;  // from the north pole (+z)
    for (int i = 0; i < slices; ++i) {
      const double phi = 2 * std::numbers::pi * i / slices;
      const double ring = (j == 0 || j == stacks) ? 0.0 : r * std::sin(theta);  // exact poles, welded
      m.vertices.push_back({c[0] + ring * std::cos(phi), c[1] + ring * std::sin(phi),
                            c[2] + (j == 0 ? r : j == stacks ? -r : r * std::cos(theta))});
    }
  }
  auto at = [&](int j, int i) { return uint32_t(j * slices + (i % slices)); };
  for (int j = 0; j < stacks; ++j)
    for (int i = 0; i < slices; ++i) {
      // Poles repeat one vertex per slice; Scene::add_mesh welds them and drops the degenerate halves.
      m.triangles.push_back({at(j, i), at(j + 1, i), at(j + 1, i + 1)});
      m.triangles.push_back({at(j, i), at(j + 1, i + 1), at(j, i + 1)});
    }
  return m;
}

Vec3 centroid(const Mesh& m, const std::array<uint32_t, 3>& t) {
  Vec3 c{0, 0, 0};
  for (uint32_t v : t)
    for (int k = 0; k < 3; ++k) c[k] += m.vertices[v][k] / 3;
  return c;
}

// The mesh without the triangles whose centroid satisfies `drop`.
template <typename Drop>
Mesh without(const Mesh& m, Drop drop) {
  Mesh out{m.vertices, {}};
  for (const auto& t : m.triangles)
    if (!drop(centroid(m, t))) out.triangles.push_back(t);
  return out;
}

// Drops exactly one triangle whose centroid satisfies `drop` (the first, in mesh order).
template <typename Drop>
Mesh without_one(const Mesh& m, Drop drop) {
  Mesh out{m.vertices, {}};
  bool dropped = false;
  for (const auto& t : m.triangles) {
    const Vec3 c = centroid(m, t);
    const bool degenerate = t[0] == t[1] || t[1] == t[2] || t[0] == t[2] ||
                            m.vertices[t[0]] == m.vertices[t[1]] || m.vertices[t[1]] == m.vertices[t[2]] ||
                            m.vertices[t[0]] == m.vertices[t[2]];
    if (!dropped && !degenerate && drop(c)) {
      dropped = true;
      continue;
    }
    out.triangles.push_back(t);
  }
  EXPECT_TRUE(dropped);
  return out;
}

void add_ground(Scene& scene, double z) {
  std::vector<Vec3> v{{-3, -3, z}, {3, -3, z}, {-3, 3, z}, {3, 3, z}};
  scene.add_mesh("ground", v, Triangles{{0, 1, 3}, {0, 3, 2}});
}

Scene scene_of(const Mesh& m, bool ground = true) {
  Scene scene;
  scene.add_mesh("sphere", m.vertices, m.triangles);
  if (ground) add_ground(scene, -1.5);
  return scene;
}

struct Rendered {
  LightFrame frame;
  TileIntervals tile;        // the build's: centre intervals capped by the fast cap pass
  TileIntervals reference;   // verify's: centre intervals capped by the brute-force reference
};

constexpr uint32_t kResolution = 64;
constexpr float kMargin = 1e-3f;

// The sun straight above (light travels -z); caps on, as the build has them.
Rendered render(const Scene& scene) {
  WorldBounds bounds{{-3, -3, -1.5}, {3, 3, 1}};  // the same frame with and without the ground's bounds
  auto frame = LightFrame::fit({0, 0, -1}, bounds, kResolution);
  EXPECT_TRUE(frame.ok());
  auto layout = TileLayout::make(kResolution, kResolution);
  LightSpaceScene light_scene(scene, *frame, *layout);
  auto device = EmbreeDevice::create();
  EXPECT_TRUE(device.ok());
  DualDepthOptions options;
  options.exit_margin = kMargin;
  options.cap_exits_at_receiver_surfaces = true;
  DualDepthRenderer renderer(*device, light_scene, options);
  auto tile = renderer.render({0, 0});
  auto centre = renderer.render_centre({0, 0});
  EXPECT_TRUE(tile.ok() && centre.ok());
  apply_reference_caps(light_scene, {0, 0}, ReceiverContract::anywhere, 1e-6, kMargin, *centre);
  return {*frame, std::move(*tile), std::move(*centre)};
}

DepthInterval texel_at(const Rendered& r, double x, double y) {
  LightSpacePoint p = r.frame.to_light({x, y, 0});
  return r.tile.at(uint32_t(p.u), uint32_t(p.v));
}
float depth_of(const Rendered& r, double z) { return float(r.frame.to_light({0, 0, z}).depth); }

uint64_t exits(const TileIntervals& t) {
  uint64_t n = 0;
  for (const DepthInterval& i : t.texels) n += i.upper > i.lower && i.lower < 1.0f;
  return n;
}

// The build's caps are never above the reference's by more than kCapUlps (store_verifier.hpp).
void expect_reference_agrees(const Rendered& r) {
  ASSERT_EQ(r.tile.texels.size(), r.reference.texels.size());
  for (size_t i = 0; i < r.tile.texels.size(); ++i) {
    const DepthInterval &built = r.tile.texels[i], &reference = r.reference.texels[i];
    EXPECT_EQ(built.lower, reference.lower) << "texel " << i;
    if (std::isinf(reference.upper)) {  // a miss
      EXPECT_EQ(built.upper, reference.upper) << "texel " << i;
      continue;
    }
    EXPECT_LE(built.upper, std::nextafter(std::nextafter(reference.upper, 2.0f), 2.0f)) << "texel " << i;
    EXPECT_GE(built.upper, std::nextafter(std::nextafter(reference.upper, -1.0f), -1.0f)) << "texel " << i;
  }
}

const Mesh kSphere = sphere({0, 0, 0}, 1, 48, 24);

TEST(NearlyClosed, SphereWithOneTriangleRemovedIsAcceptedAndExitsAsTheClosedSphere) {
  Scene closed = scene_of(kSphere);
  ASSERT_EQ(closed.meshes[0].kind, MeshKind::closed);
  // A triangle of the lower hemisphere (facing away from the sun): first hits are unchanged.
  Scene holed = scene_of(without_one(kSphere, [](const Vec3& c) { return c[2] < -0.5 && c[0] > 0.3; }));
  ASSERT_EQ(holed.meshes[0].kind, MeshKind::open);
  EXPECT_EQ(holed.meshes[0].boundary_edges, 3u);
  const NearlyClosedReport report = close_nearly_closed_meshes(holed, {});
  ASSERT_EQ(report.meshes.size(), 2u) << "the sphere and the ground are tested";
  EXPECT_TRUE(report.meshes[0].accepted) << report.meshes[0].reason;
  EXPECT_FALSE(report.meshes[1].accepted) << "a lone quad is no solid";
  EXPECT_EQ(holed.meshes[0].kind, MeshKind::closed);
  EXPECT_EQ(holed.meshes[1].kind, MeshKind::open);
  EXPECT_EQ(holed.patch_triangles.size(), 1u) << "a triangular hole is patched by the triangle itself";
  EXPECT_LT(report.meshes[0].ambiguous_area, 0.01);

  const Rendered a = render(closed), b = render(holed);
  EXPECT_GT(exits(a.tile), 300u) << "the sphere covers about 360 texels";
  EXPECT_EQ(exits(a.tile), exits(b.tile));
  for (size_t i = 0; i < a.tile.texels.size(); ++i) {
    EXPECT_EQ(a.tile.texels[i].lower, b.tile.texels[i].lower) << "texel " << i;
    EXPECT_NEAR(a.tile.texels[i].upper, b.tile.texels[i].upper, 1e-6) << "texel " << i;
  }
  expect_reference_agrees(b);
}

TEST(NearlyClosed, WithoutTheTestTheHoledSphereIsOneSided) {
  Scene holed = scene_of(without_one(kSphere, [](const Vec3& c) { return c[2] < -0.5 && c[0] > 0.3; }));
  const Rendered r = render(holed);
  EXPECT_EQ(exits(r.tile), 0u) << "an open first hit gives upper = lower";
}

TEST(NearlyClosed, LargeHoleIsRefused) {
  // A bowl: the upper third of the sphere cut away (about a quarter of its area).
  Scene bowl = scene_of(without(kSphere, [](const Vec3& c) { return c[2] > 0.5; }));
  const NearlyClosedReport report = close_nearly_closed_meshes(bowl, {});
  ASSERT_FALSE(report.meshes.empty());
  EXPECT_FALSE(report.meshes[0].accepted);
  EXPECT_GT(report.meshes[0].ambiguous_area, 0.01);
  EXPECT_EQ(bowl.meshes[0].kind, MeshKind::open);
  EXPECT_TRUE(bowl.patch_triangles.empty());
  EXPECT_EQ(exits(render(bowl).tile), 0u);
}

// The sphere with the faces whose centroid passes `pick` turned inside out.
Mesh flipped_where(const std::function<bool(const Vec3&)>& pick, bool only_one) {
  Mesh flipped = kSphere;
  for (auto& t : flipped.triangles) {
    if (!pick(centroid(flipped, t))) continue;
    std::swap(t[1], t[2]);
    if (only_one) break;
  }
  return flipped;
}

TEST(NearlyClosed, OneFlippedFaceIsAcceptedAndStaysConservativeThere) {
  Scene scene = scene_of(flipped_where([](const Vec3& c) { return c[2] > 0.5 && c[0] > 0.3 && c[1] > 0.1; }, true),
                         false);
  EXPECT_EQ(scene.meshes[0].misoriented_edges, 3u);
  const NearlyClosedReport report = close_nearly_closed_meshes(scene, {});
  // Each misoriented edge is a boundary edge twice over: the patch is the face twice, the right way
  // round, so mesh + patch is the sphere again (a cycle), and |w_patch| ~ 1 near the face. The whole
  // winding number at the face's own samples is 1 outside and 0 inside: misplaced, but on a share of
  // the area far below max_misplaced_area, so the sphere is a solid.
  EXPECT_EQ(report.meshes[0].patch_triangles, 2u);
  EXPECT_GT(report.meshes[0].max_deviation, 0.5);
  EXPECT_EQ(report.meshes[0].full_samples, report.meshes[0].samples) << "a small mesh is checked everywhere";
  EXPECT_EQ(report.meshes[0].misplaced_samples, 1u);
  EXPECT_GT(report.meshes[0].misplaced_area, 0.0);
  EXPECT_LT(report.meshes[0].misplaced_area, 0.01);
  EXPECT_TRUE(report.meshes[0].accepted) << report.meshes[0].reason;
  const Rendered flipped = render(scene);
  const Rendered sphere = render(scene_of(kSphere, false));
  // The flipped face's texels see a back face first (no exit there, upper = lower); every other texel
  // exits as the closed sphere's, and the brute-force reference agrees everywhere.
  EXPECT_LT(exits(flipped.tile), exits(sphere.tile));
  EXPECT_GT(exits(flipped.tile), exits(sphere.tile) - 20) << "only the face's few texels lose their exit";
  for (size_t i = 0; i < flipped.tile.texels.size(); ++i)
    EXPECT_LE(flipped.tile.texels[i].upper, sphere.tile.texels[i].upper + 1e-6f) << "texel " << i;
  expect_reference_agrees(flipped);

  NearlyClosedOptions strict;
  strict.max_misplaced_area = 0;
  Scene again = scene_of(flipped_where([](const Vec3& c) { return c[2] > 0.5 && c[0] > 0.3 && c[1] > 0.1; }, true),
                         false);
  EXPECT_FALSE(close_nearly_closed_meshes(again, strict).meshes[0].accepted) << "0 refuses any misplaced sample";
}

TEST(NearlyClosed, ThreadsDoNotChangeTheTest) {
  const Mesh flipped = flipped_where([](const Vec3& c) { return c[2] > 0.9; }, false);
  const Mesh holed = without_one(kSphere, [](const Vec3& c) { return c[2] < -0.5 && c[0] > 0.3; });
  for (const Mesh* mesh : {&flipped, &holed}) {
    Scene one = scene_of(*mesh, false), three = scene_of(*mesh, false);
    NearlyClosedOptions parallel;
    parallel.threads = 3;
    const MeshClosingReport a = close_nearly_closed_meshes(one, {}).meshes[0];
    const MeshClosingReport b = close_nearly_closed_meshes(three, parallel).meshes[0];
    EXPECT_EQ(a.accepted, b.accepted);
    EXPECT_EQ(a.full_samples, b.full_samples);
    EXPECT_EQ(a.misplaced_samples, b.misplaced_samples);
    EXPECT_EQ(a.misplaced_area, b.misplaced_area);
    EXPECT_EQ(a.max_deviation, b.max_deviation);
    EXPECT_EQ(a.ambiguous_area, b.ambiguous_area);
    EXPECT_EQ(a.patched_volume, b.patched_volume);
  }
}

TEST(NearlyClosed, FlippedCapIsRefused) {
  // Every face above z = 0.9 flipped: about 5 % of the sphere's area has the wrong winding number.
  Scene scene = scene_of(flipped_where([](const Vec3& c) { return c[2] > 0.9; }, false), false);
  const NearlyClosedReport report = close_nearly_closed_meshes(scene, {});
  EXPECT_GT(report.meshes[0].misplaced_area, 0.01);
  EXPECT_FALSE(report.meshes[0].accepted);
  EXPECT_EQ(scene.meshes[0].kind, MeshKind::open);
  EXPECT_EQ(exits(render(scene).tile), 0u);
}

// An axis-aligned box [lo, hi] appended to the vertices and triangles, outward facing.
void add_box(std::vector<Vec3>& v, Triangles& t, Vec3 lo, Vec3 hi) {
  const uint32_t base = uint32_t(v.size());
  for (int i = 0; i < 8; ++i) v.push_back({(i & 1) ? hi[0] : lo[0], (i & 2) ? hi[1] : lo[1], (i & 4) ? hi[2] : lo[2]});
  const Triangles faces{{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                        {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  for (auto f : faces) t.push_back({f[0] + base, f[1] + base, f[2] + base});
}

TEST(NearlyClosed, TouchingPartsWithAFaceBetweenThemAreRefused) {
  // Two boxes sharing a whole face, both faces kept (as IFC exports beams that touch): the mesh is a
  // cycle (the shared face's edges are used four times, balanced), but the faces between the boxes
  // lie inside the solid with winding number 1 on both sides: real receivers there would be inside.
  std::vector<Vec3> v;
  Triangles t;
  add_box(v, t, {-1, -1, -1}, {0, 1, 1});
  add_box(v, t, {0, -1, -1}, {1, 1, 1});
  Scene scene;
  scene.add_mesh("touching boxes", v, t);
  EXPECT_EQ(scene.meshes[0].kind, MeshKind::open);
  EXPECT_GT(scene.meshes[0].non_manifold_edges, 0u);
  const NearlyClosedReport report = close_nearly_closed_meshes(scene, {});
  EXPECT_EQ(report.meshes[0].patch_triangles, 0u);
  EXPECT_EQ(report.meshes[0].misplaced_samples, 4u) << "the four triangles between the boxes";
  EXPECT_FALSE(report.meshes[0].accepted);
}

// A small hole at the north pole (the cap of triangles around it), facing the sun.
Mesh pole_hole(double above) {
  return without(kSphere, [above](const Vec3& c) { return c[2] > above; });
}

TEST(NearlyClosed, RayThroughAHoleFacingTheLightStaysConservative) {
  Scene scene = scene_of(pole_hole(0.99));
  const NearlyClosedReport report = close_nearly_closed_meshes(scene, {});
  ASSERT_TRUE(report.meshes[0].accepted) << report.meshes[0].reason << " ambiguous " << report.meshes[0].ambiguous_area;
  EXPECT_EQ(report.meshes[0].loops, 1u);
  const Rendered r = render(scene);
  // Through the hole the first real surface is the sphere's inside bottom (a back face): upper = lower,
  // never the patch's depth (the patch is no surface).
  const DepthInterval through = texel_at(r, 0.01, 0.01);
  EXPECT_NEAR(through.lower, depth_of(r, -1), 2e-3);
  EXPECT_EQ(through.upper, through.lower);
  // Beside the hole the ray enters the sphere's top and leaves at its bottom.
  const DepthInterval beside = texel_at(r, 0.5, 0.01);
  EXPECT_NEAR(beside.lower, depth_of(r, std::sqrt(1 - 0.25)), 0.02);
  EXPECT_GT(beside.upper, depth_of(r, 0));
  expect_reference_agrees(r);
}

TEST(NearlyClosed, RayLeavingThroughAHoleExitsAtThePatch) {
  // The same hole at the south pole, facing the ground.
  Scene scene = scene_of(without(kSphere, [](const Vec3& c) { return c[2] < -0.99; }));
  const NearlyClosedReport report = close_nearly_closed_meshes(scene, {});
  ASSERT_TRUE(report.meshes[0].accepted) << report.meshes[0].reason;
  const Rendered r = render(scene);
  const DepthInterval through = texel_at(r, 0.01, 0.01);
  EXPECT_NEAR(through.lower, depth_of(r, 1), 2e-3);
  // The patch (at the hole's rim, z ~ -0.991) bounds the solid: the exit is there less the margin,
  // above the ground seen through the hole, which stays shadowed.
  const float rim = depth_of(r, -std::cos(std::numbers::pi / 24));
  EXPECT_GT(through.upper, depth_of(r, 0));
  EXPECT_LE(through.upper, rim - kMargin + 1e-6f);
  EXPECT_LT(through.upper + kMargin, depth_of(r, -1.5));
  expect_reference_agrees(r);
}

TEST(NearlyClosed, BalancedNonManifoldEdgesNeedNoPatch) {
  // Two boxes sharing an edge, as one mesh: four uses of that edge, two
  // each way. The mesh is a cycle already; it is accepted with no patch.
  std::vector<Vec3> v;
  Triangles t;
  add_box(v, t, {-1, -1, -1}, {0, 0, 1});
  add_box(v, t, {0, 0, -1}, {1, 1, 1});
  Scene scene;
  scene.add_mesh("boxes", v, t);
  EXPECT_EQ(scene.meshes[0].kind, MeshKind::open);
  EXPECT_EQ(scene.meshes[0].non_manifold_edges, 1u);
  const NearlyClosedReport report = close_nearly_closed_meshes(scene, {});
  EXPECT_TRUE(report.meshes[0].accepted) << report.meshes[0].reason;
  EXPECT_EQ(report.meshes[0].patch_triangles, 0u);
  const Rendered r = render(scene);
  const DepthInterval inside = texel_at(r, 0.5, 0.5);
  EXPECT_NEAR(inside.lower, depth_of(r, 1), 1e-6);
  EXPECT_GT(inside.upper, depth_of(r, 0));
  expect_reference_agrees(r);
}

TEST(NearlyClosed, PatchesAreALoopsReverse) {
  // Every loop's fan cancels the boundary: mesh + patch has no boundary edge left.
  Mesh holed = without(kSphere, [](const Vec3& c) { return c[2] > 0.9 || (c[2] < -0.2 && c[2] > -0.4 && c[0] > 0.8); });
  Scene welded = scene_of(holed, false);
  std::vector<Vec3> scene_vertices = welded.vertices;
  MeshPatch patch = patch_boundary_loops(scene_vertices, welded.triangles);
  EXPECT_GE(patch.loops, 2u) << "the cap and the band (the zigzag rims may split)";
  Triangles all = welded.triangles;
  all.insert(all.end(), patch.triangles.begin(), patch.triangles.end());
  MeshPatch again = patch_boundary_loops(scene_vertices, all);
  EXPECT_EQ(again.loops, 0u);
  EXPECT_TRUE(again.triangles.empty());
  // And the winding number of mesh + patch is an integer off the surface.
  EXPECT_NEAR(winding_number(scene_vertices, all, {0, 0, 0}), 1.0, 1e-9);
  EXPECT_NEAR(winding_number(scene_vertices, all, {0, 0, 2}), 0.0, 1e-9);
  EXPECT_NEAR(winding_number(scene_vertices, all, {0.2, 0.1, 0.8}), 1.0, 1e-9) << "under the patched cap";
  EXPECT_NEAR(winding_number(scene_vertices, all, {0.1, 0.1, 0.97}), 0.0, 1e-9) << "in the cut-away cap";
}

// A whole build of the holed sphere over a ground plane, verified texel by texel (the verifier closes
// the scene itself from the store's meta), and the same build with the test off has no exits.
void write_obj(const std::filesystem::path& path, const Scene& scene) {
  std::ofstream out(path);
  out.precision(17);
  for (const Vec3& p : scene.vertices) out << "v " << p[0] << ' ' << p[1] << ' ' << p[2] << '\n';
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    out << "o " << scene.meshes[m].name << '\n';
    for (uint32_t i = 0; i < scene.meshes[m].triangle_count; ++i) {
      const auto& t = scene.triangles[scene.meshes[m].first_triangle + i];
      out << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
    }
  }
}

TEST(NearlyClosed, BuildOfAHoledSphereVerifiesAndRecordsTheChoice) {
  testing::TempDir dir;
  write_obj(dir.path() / "holed.obj", scene_of(pole_hole(0.99)));
  BuildConfig config;
  config.scene_path = dir.path() / "holed.obj";
  config.store_path = dir.path() / "on";
  config.light_direction = {0.3, 0.2, -1};
  config.resolution = 256;
  config.tile_size = 128;
  config.methods = {store::Method::raw, store::Method::mh, store::Method::mmh, store::Method::dagmh};
  auto on = testing::build_and_verify_every_texel(config, config.methods);
  ASSERT_TRUE(on.has_value());
  EXPECT_EQ(on->stats["scene"]["nearly_closed"]["meshes"], 1);
  EXPECT_GT(on->stats["scene"]["nearly_closed"]["patch_triangles"].get<uint64_t>(), 0u);
  auto map = ShadowMap::open(config.store_path);
  ASSERT_TRUE(map.ok());
  EXPECT_TRUE((*map)->meta().nearly_closed);
  EXPECT_DOUBLE_EQ((*map)->meta().nearly_closed_tolerance, 0.1);

  config.close_nearly_closed = false;
  config.store_path = dir.path() / "off";
  auto off = testing::build_and_verify_every_texel(config, config.methods);
  ASSERT_TRUE(off.has_value());
  EXPECT_EQ(off->stats["scene"]["nearly_closed"]["meshes"], 0);
  auto off_map = ShadowMap::open(config.store_path);
  ASSERT_TRUE(off_map.ok());
  EXPECT_FALSE((*off_map)->meta().nearly_closed);
  EXPECT_NE((*off_map)->meta().config_hash, (*map)->meta().config_hash) << "resumes and merges do not mix them";
  EXPECT_LT(on->stats["bytes_by_method"]["dagmh"].get<uint64_t>(), off->stats["bytes_by_method"]["dagmh"].get<uint64_t>())
      << "the sphere's texels gain exits";
}

}  // namespace
}  // namespace shadowtiles
