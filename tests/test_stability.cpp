// Stability scenarios of issue #8 as assertions (fast variants; `shadowtiles stability` runs the
// full figures into STABILITY.md). Each builds real stores (Embree, LMDB in a temp dir) and compares
// answers with Embree ground truth or with another build.
//
// The central rule: a lossless method stores, per texel, a value inside the dual-depth interval
// [lower, upper]; raw stores lower. A receiver is lit when depth - bias <= value, so a lossless
// method's lit set contains raw's, and it may only add light where the receiver's depth lies inside
// the interval, i.e. inside a solid. Its false-lit count beyond raw's is therefore exactly the light
// the dual-depth rule leaks; it must be 0 (no tolerance) on the scenes below.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>

#include "builder/accuracy.hpp"
#include "builder/build_job.hpp"
#include "builder/dual_depth_renderer.hpp"
#include "builder/ground_truth.hpp"
#include "builder/light_space_scene.hpp"
#include "builder/mh_builder.hpp"
#include "builder/mh_encoder.hpp"
#include "builder/mh_verify.hpp"
#include "builder/mmh_merger.hpp"
#include "builder/receiver_sampler.hpp"
#include "builder/scene_loader.hpp"
#include "builder/tile_encoder.hpp"
#include "client/shadow_map.hpp"
#include "tests/testing_support.hpp"

namespace shadowtiles {
namespace {

using testing::TempDir;

bool interval_exact(store::Method m) {
  return m == store::Method::mh || m == store::Method::mmh || m == store::Method::dagmh;
}

// raw first, then every method the builder supports whose answers must stay inside the interval.
std::vector<store::Method> lossless_methods() {
  std::vector<store::Method> methods{store::Method::raw};
  for (store::Method m : store::all_methods())
    if (interval_exact(m) && builder_supports(m)) methods.push_back(m);
  return methods;
}

void write_text(const std::filesystem::path& file, const std::string& text) {
  std::ofstream out(file);
  out << text;
}

// A 20 x 20 floor and a room over its middle whose four walls and roof are one-sided quads.
std::string open_roof_room_obj() {
  return "v -10 -10 0\nv 10 -10 0\nv 10 10 0\nv -10 10 0\n"   // floor 1-4
         "v -5 -5 0\nv 5 -5 0\nv 5 5 0\nv -5 5 0\n"           // room corners at 0: 5-8
         "v -5 -5 3\nv 5 -5 3\nv 5 5 3\nv -5 5 3\n"           // at 3: 9-12
         "o floor\nf 1 2 3\nf 1 3 4\n"
         "o roof\nf 9 10 11\nf 9 11 12\n"
         "o walls\nf 5 6 10\nf 5 10 9\nf 6 7 11\nf 6 11 10\nf 7 8 12\nf 7 12 11\nf 8 5 9\nf 8 9 12\n";
}

// A 40 x 40 floor with a closed wall box (10 long, 4 high, `thickness` along x) across its middle.
std::string thin_wall_obj(double thickness) {
  const double h = thickness / 2;
  char text[1024];
  std::snprintf(text, sizeof text,
                "v -20 -20 0\nv 20 -20 0\nv 20 20 0\nv -20 20 0\no floor\nf 1 2 3\nf 1 3 4\n"
                "v %.17g -5 0\nv %.17g -5 0\nv %.17g 5 0\nv %.17g 5 0\n"
                "v %.17g -5 4\nv %.17g -5 4\nv %.17g 5 4\nv %.17g 5 4\n"
                "o wall\nf 5 7 8\nf 5 8 6\nf 9 10 12\nf 9 12 11\nf 5 6 10\nf 5 10 9\n"
                "f 7 11 12\nf 7 12 8\nf 5 9 11\nf 5 11 7\nf 6 8 12\nf 6 12 10\n",
                -h, h, -h, h, -h, h, -h, h);
  return text;
}

struct Measured {
  std::vector<PointAccuracy> counts;       // per method of `methods`
  std::vector<std::vector<uint8_t>> lit;    // answers per method
  std::vector<Receiver> receivers;
};

BuildConfig make_config(const std::filesystem::path& scene, const std::filesystem::path& store, uint32_t resolution,
                        const Vec3& light, const std::vector<store::Method>& methods) {
  BuildConfig config;
  config.scene_path = scene;
  config.store_path = store;
  config.resolution = resolution;
  config.tile_size = std::min(resolution, 1024u);
  config.light_direction = light;
  config.methods = methods;
  config.overwrite = true;
  return config;
}

// Builds and judges every method on `receiver_count` uniform receivers against ground truth.
Measured build_and_measure(const BuildConfig& config, size_t receiver_count) {
  Measured out;
  auto summary = run_build(config);
  EXPECT_TRUE(summary.ok()) << summary.error().message;
  if (!summary) return out;
  auto scene = load_scene(config.scene_path, config.load);
  EXPECT_TRUE(scene.ok());
  auto device = EmbreeDevice::create();
  GroundTruth truth(*device, *scene, config.light_direction);
  out.receivers = sample_receivers(*scene, receiver_count, 7);
  auto map = ShadowMap::open(config.store_path);
  EXPECT_TRUE(map.ok());
  const std::vector<uint8_t> truth_lit = point_truth(truth, out.receivers);
  for (store::Method m : config.methods) {
    std::vector<uint8_t> lit;
    auto counts = point_accuracy(**map, m, out.receivers, truth_lit, {}, &lit);
    EXPECT_TRUE(counts.ok());
    out.counts.push_back(*counts);
    out.lit.push_back(std::move(lit));
  }
  return out;
}

uint64_t differing(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  uint64_t n = 0;
  for (size_t i = 0; i < a.size(); ++i) n += a[i] != b[i];
  return n;
}

void print_counts(const char* what, const BuildConfig& config, const Measured& m) {
  for (size_t k = 0; k < config.methods.size(); ++k)
    std::printf("[ figures  ] %s %s: false lit %llu, false shadowed %llu of %llu\n", what,
                store::method_name(config.methods[k]), (unsigned long long)m.counts[k].false_lit,
                (unsigned long long)m.counts[k].false_shadowed, (unsigned long long)m.counts[k].receivers);
}

// --- 1. Open geometry --------------------------------------------------------------------------

TEST(StabilityOpenGeometry, OneSidedRoofLeaksNothingAndTheFarPlaneRuleWould) {
  TempDir dir;
  const auto scene = dir.path() / "room.obj";
  write_text(scene, open_roof_room_obj());
  const Vec3 light = *light_direction_from_sun(135, 60, UpAxis::z);
  BuildConfig config = make_config(scene, dir.path() / "ours", 256, light, lossless_methods());
  Measured ours = build_and_measure(config, 4000);
  ASSERT_EQ(ours.counts.size(), config.methods.size());
  print_counts("room, exit = entry", config, ours);
  for (size_t k = 1; k < config.methods.size(); ++k)
    EXPECT_EQ(differing(ours.lit[k], ours.lit[0]), 0u) << store::method_name(config.methods[k])
                                                       << ": open meshes have zero-width intervals";

  config.store_path = dir.path() / "far_plane";
  config.open_exit_at_far_plane = true;
  Measured far = build_and_measure(config, 4000);
  ASSERT_EQ(far.counts.size(), config.methods.size());
  print_counts("room, far-plane exit", config, far);
  EXPECT_EQ(far.counts[0].false_lit, ours.counts[0].false_lit) << "raw (the lower bound) ignores the exit rule";
  for (size_t k = 1; k < config.methods.size(); ++k)
    EXPECT_GT(far.counts[k].false_lit, ours.counts[k].false_lit + 20)
        << store::method_name(config.methods[k]) << ": the floor under the roof must light up under that rule";
}

TEST(StabilityOpenGeometry, OpenScanAnswersAsRaw) {
  TempDir dir;
  BuildConfig config = make_config(testing::shared_scene("bunny/stanford-bunny.obj"), dir.path() / "s", 512,
                                   *light_direction_from_sun(135, 45, UpAxis::y), lossless_methods());
  config.load.up = UpAxis::y;
  config.close_nearly_closed = false;  // the open scan as such (accepted as a solid by default)
  Measured m = build_and_measure(config, 4000);
  ASSERT_EQ(m.counts.size(), config.methods.size());
  for (size_t k = 1; k < config.methods.size(); ++k) EXPECT_EQ(differing(m.lit[k], m.lit[0]), 0u);
}

TEST(StabilityOpenGeometry, NearlyClosedScanLeaksNoMoreThanRaw) {
  // The default build accepts the bunny (holes in its base) as a solid: exits appear, raw's false-lit
  // receivers stay the only ones (docs/receiver-contracts.md, "Nearly closed solids").
  TempDir dir;
  BuildConfig config = make_config(testing::shared_scene("bunny/stanford-bunny.obj"), dir.path() / "s", 512,
                                   *light_direction_from_sun(135, 45, UpAxis::y), lossless_methods());
  config.load.up = UpAxis::y;
  ASSERT_TRUE(config.close_nearly_closed);
  Measured m = build_and_measure(config, 4000);
  ASSERT_EQ(m.counts.size(), config.methods.size());
  print_counts("bunny, nearly closed", config, m);
  uint64_t differ = 0;
  for (size_t k = 1; k < config.methods.size(); ++k) {
    EXPECT_LE(m.counts[k].false_lit, m.counts[0].false_lit) << store::method_name(config.methods[k]);
    differ += differing(m.lit[k], m.lit[0]);
  }
  EXPECT_GT(differ, 0u) << "exits exist: some answers differ from raw's (fewer false shadows)";
}

// --- 2. Thin walls -----------------------------------------------------------------------------

TEST(StabilityThinWalls, WallsOneTexelAndThinnerLeakNothing) {
  const uint32_t resolution = 256;
  const Vec3 light = *light_direction_from_sun(90, 30, UpAxis::z);  // sun in the east
  auto frame = LightFrame::fit(light, {{-20, -20, 0}, {20, 20, 4}}, resolution);
  ASSERT_TRUE(frame.ok());
  for (double texels : {1.0, 0.5, 0.1}) {
    TempDir dir;
    const auto scene = dir.path() / "wall.obj";
    write_text(scene, thin_wall_obj(texels * frame->texel_size()));
    BuildConfig config = make_config(scene, dir.path() / "s", resolution, light, lossless_methods());
    Measured m = build_and_measure(config, 4000);
    ASSERT_EQ(m.counts.size(), config.methods.size());
    for (size_t k = 1; k < config.methods.size(); ++k)
      EXPECT_EQ(m.counts[k].false_lit, m.counts[0].false_lit)
          << store::method_name(config.methods[k]) << " wall " << texels << " texel";
    // Floor points well inside the wall's shadow (west of it; the shadow is 4 / tan 30 = 6.9 long),
    // away from its edges by more than two texels: every method answers shadowed.
    auto map = ShadowMap::open(config.store_path);
    ASSERT_TRUE(map.ok());
    const double margin = 3 * frame->texel_size();
    for (store::Method method : config.methods)
      for (double x = -1.0; x > -6.5; x -= 0.37)
        for (double y = -4.5 + margin; y < 4.5 - margin; y += 0.61) {
          auto answer = (*map)->query({x, y, 0.0}, method);
          ASSERT_TRUE(answer.ok());
          EXPECT_FALSE(answer->lit) << store::method_name(method) << " wall " << texels << " at " << x << "," << y;
        }
  }
}

TEST(StabilityThinWalls, ClosedBustLeaksNoMoreThanRaw) {
  TempDir dir;
  BuildConfig config = make_config(testing::shared_scene("nefertiti/nefertiti.obj"), dir.path() / "s", 512,
                                   *light_direction_from_sun(135, 45, UpAxis::z), lossless_methods());
  config.cap_exits_at_receiver_surfaces = true;  // `build --exit-caps`: the fix under test
  Measured m = build_and_measure(config, 4000);
  ASSERT_EQ(m.counts.size(), config.methods.size());
  print_counts("nefertiti 512", config, m);
  for (size_t k = 1; k < config.methods.size(); ++k)
    EXPECT_EQ(m.counts[k].false_lit, m.counts[0].false_lit) << store::method_name(config.methods[k]);
}

// --- 3. Grazing sun ----------------------------------------------------------------------------

TEST(StabilityGrazingSun, TerrainLeaksNoMoreThanRawAtLowSun) {
  for (double elevation : {2.0, 10.0}) {
    TempDir dir;
    BuildConfig config = make_config(testing::shared_scene("terragen/RealisticTerrain.ter"), dir.path() / "s", 512,
                                     *light_direction_from_sun(135, elevation, UpAxis::z), lossless_methods());
    config.load.heightfield_meshes = {"*"};
    config.cap_exits_at_receiver_surfaces = true;  // `build --exit-caps`: the fix under test
    Measured m = build_and_measure(config, 4000);
    ASSERT_EQ(m.counts.size(), config.methods.size());
    print_counts(elevation == 2 ? "terragen el 2" : "terragen el 10", config, m);
    for (size_t k = 1; k < config.methods.size(); ++k)
      EXPECT_EQ(m.counts[k].false_lit, m.counts[0].false_lit)
          << store::method_name(config.methods[k]) << " elevation " << elevation;
  }
}

// --- 4. Tile seams -----------------------------------------------------------------------------

TEST(StabilityTileSeams, BordersAndFourTileCornersAnswerAsOneTile) {
  TempDir dir;
  const uint32_t resolution = 256, small = 32;
  std::vector<store::Method> methods;
  for (store::Method m : store::all_methods())
    if (builder_supports(m)) methods.push_back(m);
  for (uint32_t tile : {resolution, small}) {
    BuildConfig config = make_config(testing::shared_scene("nefertiti/nefertiti.obj"),
                                     dir.path() / std::to_string(tile), resolution,
                                     *light_direction_from_sun(135, 45, UpAxis::z), methods);
    config.tile_size = tile;
    ASSERT_TRUE(run_build(config).ok());
  }
  auto one = ShadowMap::open(dir.path() / std::to_string(resolution));
  auto many = ShadowMap::open(dir.path() / std::to_string(small));
  ASSERT_TRUE(one.ok() && many.ok());
  const LightFrame& frame = (*one)->frame();
  const double bias = frame.depth_from_world((*one)->meta().default_bias);
  std::vector<Vec3> points;
  std::mt19937_64 random(3);
  std::uniform_real_distribution<double> unit(0, 1);
  uint64_t near_surface = 0;
  for (uint32_t k = 1; k < resolution / small; ++k)
    for (uint32_t j = 0; j < resolution / small; ++j) {
      // Exactly on the border, and at the tile corner (PCF kernels there span four tiles).
      for (LightSpacePoint p : {LightSpacePoint{double(k * small), (j + unit(random)) * small, 0},
                                LightSpacePoint{(j + unit(random)) * small, double(k * small), 0},
                                LightSpacePoint{double(k * small), double(j * small), 0}}) {
        auto value = (*one)->texel_value(store::Method::raw, uint32_t(p.u), uint32_t(p.v));
        ASSERT_TRUE(value.ok());
        // Near the stored surface, where answers flip, when there is one.
        p.depth = *value < 1 ? *value + (unit(random) - 0.5) * 4 * bias : unit(random);
        near_surface += *value < 1;
        points.push_back(frame.to_world(p));
      }
    }
  ASSERT_GT(near_surface, 20u) << "the borders must cross the bust";
  // Raw (value = lower) must answer identically. Interval methods may store any value in [lower,
  // upper] and each tiling builds its own hierarchy, so two tilings may answer differently for a
  // depth inside the interval; never where raw is lit (depth <= lower + bias, so both must be lit).
  for (store::Method method : methods)
    for (const Vec3& p : points) {
      auto a = (*one)->query(p, method), b = (*many)->query(p, method);
      ASSERT_TRUE(a.ok() && b.ok());
      if (method == store::Method::raw) {
        EXPECT_EQ(a->lit, b->lit);
        // An absent (empty) tile and a stored miss both answer lit; their values differ (inf vs 1).
        // Otherwise stored depths are bit-identical (hit depths re-evaluated in global doubles).
        if (!a->empty_tile && !b->empty_tile) {
          EXPECT_EQ(a->value, b->value);
        }
        for (unsigned kernel : {3u, 5u, 9u}) {
          auto fa = (*one)->query_pcf(p, method, kernel), fb = (*many)->query_pcf(p, method, kernel);
          ASSERT_TRUE(fa.ok() && fb.ok());
          EXPECT_EQ(*fa, *fb) << "raw PCF " << kernel;
        }
      } else if (a->lit != b->lit) {
        auto raw = (*one)->query(p, store::Method::raw);
        ASSERT_TRUE(raw.ok());
        EXPECT_FALSE(raw->lit) << store::method_name(method) << ": tilings differ where raw is lit";
      }
    }
}

// The renderer's output itself, on real scenes: one tile and 128^2 tiles give bit-identical
// intervals (each tile's BVH holds tile-local floats, so Embree's hit distance is rounded per
// tiling; every hit's depth is re-evaluated from its triangle's global double plane). Rendered as
// the build job does (exit margin, exit caps).
TEST(StabilityTileSeams, RenderedIntervalsAreBitIdenticalUnderAnyTiling) {
  struct Subject {
    const char* file;
    bool heightfield;
    double elevation;
  };
  auto device = EmbreeDevice::create();
  ASSERT_TRUE(device.ok());
  const uint32_t resolution = 1024, small = 128;
  for (const Subject& subject : {Subject{"terragen/RealisticTerrain.ter", true, 30},
                                 Subject{"nefertiti/nefertiti.obj", false, 45}}) {
    LoadOptions load;
    if (subject.heightfield) load.heightfield_meshes = {"*"};
    auto scene = load_scene(testing::shared_scene(subject.file), load);
    ASSERT_TRUE(scene.ok());
    auto frame = LightFrame::fit(*light_direction_from_sun(135, subject.elevation, UpAxis::z), scene->bounds,
                                 resolution);
    ASSERT_TRUE(frame.ok());
    DualDepthOptions options;
    options.exit_margin = float(frame->depth_from_world(4 * frame->texel_size()));
    options.cap_exits_at_receiver_surfaces = true;
    auto whole_layout = TileLayout::make(resolution, resolution), tiled_layout = TileLayout::make(resolution, small);
    LightSpaceScene whole_scene(*scene, *frame, *whole_layout), tiled_scene(*scene, *frame, *tiled_layout);
    auto whole = DualDepthRenderer(*device, whole_scene, options).render({0, 0});
    ASSERT_TRUE(whole.ok());
    DualDepthRenderer tiled_renderer(*device, tiled_scene, options);
    uint64_t differing_texels = 0, hits = 0, exits = 0;
    std::string first_differences;
    for (uint32_t ty = 0; ty < resolution / small; ++ty)
      for (uint32_t tx = 0; tx < resolution / small; ++tx) {
        auto tile = tiled_renderer.render({tx, ty});
        ASSERT_TRUE(tile.ok());
        for (uint32_t v = 0; v < small; ++v)
          for (uint32_t u = 0; u < small; ++u) {
            const DepthInterval& a = tile->at(u, v);
            const DepthInterval& b = whole->at(tx * small + u, ty * small + v);
            if (a.lower != b.lower || a.upper != b.upper) {
              if (++differing_texels <= 5) {
                char line[200];
                std::snprintf(line, sizeof line, "\n  texel (%u, %u): [%.9g, %.9g] tiled, [%.9g, %.9g] whole",
                              tx * small + u, ty * small + v, a.lower, a.upper, b.lower, b.upper);
                first_differences += line;
              }
            }
            hits += a.lower < 1;
            exits += a.upper > a.lower && a.lower < 1;
          }
      }
    EXPECT_EQ(differing_texels, 0u) << subject.file << first_differences;
    EXPECT_GT(hits, uint64_t(resolution) * resolution / 10) << subject.file << ": the scene covers the map";
    EXPECT_GT(exits, 1000u) << subject.file << ": exits are compared too";
  }
}

// --- 5. Precision ------------------------------------------------------------------------------

// Renders the whole map of `scene` as one tile.
TileIntervals render_whole(const EmbreeDevice& device, const Scene& scene, const Vec3& light, uint32_t resolution,
                           LightFrame* frame_out) {
  auto frame = LightFrame::fit(light, scene.bounds, resolution);
  EXPECT_TRUE(frame.ok());
  *frame_out = *frame;
  auto layout = TileLayout::make(resolution, resolution);
  LightSpaceScene light_scene(scene, *frame, *layout);
  DualDepthOptions options;
  options.exit_margin = float(frame->depth_from_world(4 * frame->texel_size()));
  options.cap_exits_at_receiver_surfaces = true;  // as the build job renders
  DualDepthRenderer renderer(device, light_scene, options);
  auto tile = renderer.render({0, 0});
  EXPECT_TRUE(tile.ok());
  return std::move(*tile);
}

TEST(StabilityPrecision, TranslatedByAMillionAnswersTheSame) {
  LoadOptions load;
  load.heightfield_meshes = {"*"};
  auto scene = load_scene(testing::shared_scene("terragen/RealisticTerrain.ter"), load);
  ASSERT_TRUE(scene.ok());
  Scene moved = *scene;
  const double offset = 1e6;
  for (Vec3& p : moved.vertices)
    for (double& x : p) x += offset;
  for (int k = 0; k < 3; ++k) moved.bounds.min[k] += offset, moved.bounds.max[k] += offset;
  auto device = EmbreeDevice::create();
  ASSERT_TRUE(device.ok());
  const Vec3 light = *light_direction_from_sun(135, 20, UpAxis::z);
  LightFrame fa, fb;
  TileIntervals a = render_whole(*device, *scene, light, 512, &fa);
  TileIntervals b = render_whole(*device, moved, light, 512, &fb);
  double max_difference = 0;
  for (size_t i = 0; i < a.texels.size(); ++i)
    if (a.texels[i].lower < 1)
      max_difference = std::max(max_difference, double(std::fabs(a.texels[i].lower - b.texels[i].lower)));
  std::printf("[ figures  ] terragen + 10^6: max |lower difference| %.3g (normalised), texel %.3g m\n", max_difference,
              fa.texel_size());
  // Far below the query bias (2 texels of depth): the translation costs nothing measurable.
  EXPECT_LT(max_difference, 1e-6);
  const double bias = fa.depth_from_world(2 * fa.texel_size());
  uint64_t mismatches = 0;
  for (const Receiver& r : sample_receivers(*scene, 5000, 5)) {
    LightSpacePoint pa = fa.to_light(r.position);
    LightSpacePoint pb = fb.to_light({r.position[0] + offset, r.position[1] + offset, r.position[2] + offset});
    ASSERT_EQ(uint32_t(pa.u), uint32_t(pb.u));
    ASSERT_EQ(uint32_t(pa.v), uint32_t(pb.v));
    mismatches += (float(pa.depth - bias) <= a.at(uint32_t(pa.u), uint32_t(pa.v)).lower) !=
                  (float(pb.depth - bias) <= b.at(uint32_t(pb.u), uint32_t(pb.v)).lower);
  }
  EXPECT_EQ(mismatches, 0u);
}

TEST(StabilityPrecision, Float32DepthStepIsBelowTheBiasAt2To20) {
  LoadOptions load;
  load.heightfield_meshes = {"*"};
  auto scene = load_scene(testing::shared_scene("oahu/oahu_w158n21.ply"), load);
  ASSERT_TRUE(scene.ok());
  for (double elevation : {2.0, 30.0, 90.0}) {
    auto frame = LightFrame::fit(*light_direction_from_sun(135, elevation, UpAxis::z), scene->bounds, 1u << 20);
    ASSERT_TRUE(frame.ok());
    const double step = std::ldexp(1.0, -24) * frame->depth_range(), bias = 2 * frame->texel_size();
    std::printf("[ figures  ] oahu el %g: depth range %.6g m, float32 step %.3g m, bias at 2^20 %.3g m\n", elevation,
                frame->depth_range(), step, bias);
    EXPECT_LT(step, bias);
  }
}

// --- 6. Resolution sweep -----------------------------------------------------------------------

// Tolerance: errors are counts on a sample; two resolutions misclassify different receivers, so
// the count's change has a binomial spread of about sqrt(errors): allowed 2 sqrt(e) + 3.
TEST(StabilityResolutionSweep, LosslessErrorNeverGrowsWithResolution) {
  TempDir dir;
  std::vector<std::vector<uint64_t>> errors;  // per resolution, per method
  std::vector<store::Method> methods = lossless_methods();
  for (uint32_t resolution : {128u, 256u, 512u}) {
    BuildConfig config = make_config(testing::shared_scene("bunny/stanford-bunny.obj"), dir.path() / "s", resolution,
                                     *light_direction_from_sun(135, 45, UpAxis::y), methods);
    config.load.up = UpAxis::y;
    Measured m = build_and_measure(config, 4000);
    ASSERT_EQ(m.counts.size(), methods.size());
    errors.emplace_back();
    for (const PointAccuracy& c : m.counts) errors.back().push_back(c.false_lit + c.false_shadowed);
  }
  for (size_t r = 1; r < errors.size(); ++r)
    for (size_t k = 0; k < methods.size(); ++k) {
      const double e0 = double(errors[r - 1][k]), e1 = double(errors[r][k]);
      std::printf("[ figures  ] bunny %s: %g -> %g wrong\n", store::method_name(methods[k]), e0, e1);
      EXPECT_LE(e1, e0 + 2 * std::sqrt(e0) + 3) << store::method_name(methods[k]) << " step " << r;
    }
}

// --- 8. Hash collisions ------------------------------------------------------------------------

TEST(StabilityHashCollisions, MmhOnARealTileStaysExactWithATwoBitHash) {
  auto scene = load_scene(testing::shared_scene("nefertiti/nefertiti.obj"), {});
  ASSERT_TRUE(scene.ok());
  auto device = EmbreeDevice::create();
  ASSERT_TRUE(device.ok());
  LightFrame frame;
  TileIntervals tile = render_whole(*device, *scene, *light_direction_from_sun(135, 45, UpAxis::z), 256, &frame);
  auto mh = build_mh(tile);
  ASSERT_TRUE(mh.ok());
  for (unsigned bits : {1u, 2u, 64u}) {
    MmhMergeOptions options;
    options.hash_bits = bits;
    MmhMergeStats stats;
    auto merged = merge_mmh(*mh, options, &stats);
    ASSERT_TRUE(merged.ok());
    if (bits <= 2) {
      EXPECT_GT(stats.topology_mismatches, 0u) << "the truncated hash must collide";
    }
    auto payload = encode_mh(*merged);
    ASSERT_TRUE(payload.ok());
    auto view = MhTileView::parse(*payload);
    ASSERT_TRUE(view.ok());
    Status exact = verify_lossless(tile, *view);
    EXPECT_TRUE(exact.ok()) << bits << " bits: " << (exact.ok() ? "" : exact.error().message);
    EXPECT_GT(stats.merges, 0u);
  }
}

}  // namespace
}  // namespace shadowtiles
