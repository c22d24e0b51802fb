// MMH merge on real scene tiles: the point-indexed merge (the default) gives byte for byte the
// payload of the plain scan (MmhMergeOptions::index_point_values = false, the reference), on open
// scans (all intervals point-like), a closed bust and terrain (wide intervals: the scan path), with
// and without exit caps. Each merged tile also stays lossless, and where mmh_merge_finds_nothing
// holds the merge indeed finds nothing and MMH's bytes are MH's.
#include <gtest/gtest.h>

#include <string>

#include "builder/dual_depth_renderer.hpp"
#include "builder/embree_device.hpp"
#include "builder/light_space_scene.hpp"
#include "builder/mh_builder.hpp"
#include "builder/mh_encoder.hpp"
#include "builder/mh_verify.hpp"
#include "builder/mmh_merger.hpp"
#include "builder/scene_loader.hpp"
#include "codec/mh_decoder.hpp"
#include "testing_support.hpp"

namespace shadowtiles {
namespace {

struct SceneCase {
  std::string file;
  UpAxis up;
  double azimuth, elevation;
  bool heightfield;
  uint32_t resolution, tile;
};

struct Totals {
  uint64_t tiles = 0, merges = 0, point_blocks_tested = 0;
  uint64_t proved_nothing = 0;  // tiles where mmh_merge_finds_nothing holds (the builder stores MH's bytes)
};

Totals compare_merges(const SceneCase& c, bool exit_caps) {
  Totals totals;
  LoadOptions load;
  load.up = c.up;
  if (c.heightfield) load.heightfield_meshes = {"*"};
  auto scene = load_scene(testing::shared_scene(c.file), load);
  EXPECT_TRUE(scene.ok()) << (scene.ok() ? "" : scene.error().message);
  if (!scene.ok()) return totals;
  auto direction = light_direction_from_sun(c.azimuth, c.elevation, c.up);
  auto frame = LightFrame::fit(*direction, scene->bounds, c.resolution);
  auto layout = TileLayout::make(c.resolution, c.tile);
  EXPECT_TRUE(frame.ok() && layout.ok());
  LightSpaceScene light_scene(*scene, *frame, *layout);
  auto device = EmbreeDevice::create();
  EXPECT_TRUE(device.ok());
  DualDepthOptions options;
  options.exit_margin = float(4.0 / c.resolution);
  options.cap_exits_at_receiver_surfaces = exit_caps;
  DualDepthRenderer renderer(*device, light_scene, options);
  for (uint64_t i = 0; i < layout->tile_count(); ++i) {
    const TileCoord coord = TileLayout::from_morton_index(i);
    if (light_scene.triangles_of(coord).empty()) continue;
    auto intervals = renderer.render(coord);
    EXPECT_TRUE(intervals.ok());
    if (!intervals.ok() || intervals->all_missed()) continue;
    auto tree = build_mh(*intervals);
    EXPECT_TRUE(tree.ok());
    MmhMergeOptions reference_options;
    reference_options.index_point_values = false;
    MmhMergeStats indexed_stats, reference_stats;
    auto indexed = merge_mmh(*tree, {}, &indexed_stats);
    auto reference = merge_mmh(*tree, reference_options, &reference_stats);
    EXPECT_TRUE(indexed.ok() && reference.ok());
    const auto indexed_bytes = *encode_mh(*indexed), reference_bytes = *encode_mh(*reference);
    EXPECT_EQ(indexed_bytes, reference_bytes) << c.file << " tile " << coord.x << "," << coord.y;
    EXPECT_EQ(indexed_stats.merges, reference_stats.merges);
    if (mmh_merge_finds_nothing(*tree)) {
      EXPECT_EQ(indexed_stats.merges, 0u) << c.file << " tile " << coord.x << "," << coord.y;
      EXPECT_EQ(indexed_bytes, *encode_mh(*tree)) << c.file << " tile " << coord.x << "," << coord.y;
      ++totals.proved_nothing;
    }
    EXPECT_LE(indexed_stats.full_tests, reference_stats.full_tests);
    auto view = MhTileView::parse(indexed_bytes);
    EXPECT_TRUE(view.ok());
    MhVerifyReport report;
    EXPECT_TRUE(verify_lossless(*intervals, *view, &report).ok());
    EXPECT_EQ(report.violations, 0u);
    ++totals.tiles;
    totals.merges += indexed_stats.merges;
  }
  return totals;
}

class MmhScenes : public ::testing::TestWithParam<SceneCase> {};

TEST_P(MmhScenes, PointIndexGivesTheScansBytes) {
  for (bool caps : {false, true}) {
    const Totals t = compare_merges(GetParam(), caps);
    EXPECT_GT(t.tiles, 0u);
    RecordProperty(caps ? "merges_with_caps" : "merges", std::to_string(t.merges));
    RecordProperty(caps ? "proved_nothing_with_caps" : "proved_nothing", std::to_string(t.proved_nothing));
    // The open IFC house's full-depth tiles: where the builder skips the merge.
    if (GetParam().file.starts_with("fzk_haus")) {
      EXPECT_GT(t.proved_nothing, 0u);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(
    Shared, MmhScenes,
    ::testing::Values(SceneCase{"bunny/stanford-bunny.obj", UpAxis::y, 135, 45, false, 2048, 1024},
                      SceneCase{"fzk_haus/fzk_haus.obj", UpAxis::y, 135, 45, false, 2048, 1024},
                      SceneCase{"honolulu_airport/honolulu_airport_harbour.ply", UpAxis::z, 135, 30, false,
                                2048, 1024},
                      SceneCase{"nefertiti/nefertiti.obj", UpAxis::z, 135, 45, false, 1024, 512},
                      SceneCase{"terragen/RealisticTerrain.ter", UpAxis::z, 135, 30, true, 1024, 512}),
    [](const auto& info) {
      const std::string& f = info.param.file;
      return f.substr(0, f.find('/'));
    });

}  // namespace
}  // namespace shadowtiles
