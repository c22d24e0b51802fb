// Scenario 8: hash collisions in MMH merging. Real tiles (a closed bust, a terrain) are merged with
// the topology hash cut to a few bits, so buckets mix different topologies; the merge must still be
// exact (it compares structure and intervals in full, never trusting hash equality).
#include <fmt/format.h>

#include "bench/harness/stability_scenarios.hpp"
#include "builder/dual_depth_renderer.hpp"
#include "builder/light_space_scene.hpp"
#include "builder/mh_builder.hpp"
#include "builder/mh_encoder.hpp"
#include "builder/mh_verify.hpp"
#include "builder/mmh_merger.hpp"

namespace shadowtiles::bench {

Result<ScenarioResult> run_hash_collisions(StabilityContext& context) {
  ScenarioResult result("hash_collisions", "8. Hash collisions in MMH merging");
  const uint32_t resolution = context.options().quick ? 256 : 1024;
  result.setup = fmt::format("one {0}^2 tile per scene (dual depth from Embree), MH bottom-up, merged with the "
                             "topology hash cut to 1, 2, 4, 8 and 64 bits; every texel of the decoded MMH checked "
                             "against its interval. (DAG-MH's equivalent: tests/test_dagmh.cpp.)",
                             resolution);
  StabilityTable table{"MMH merge with a truncated hash",
                       {"scene", "hash bits", "blocks before", "blocks after", "merges", "full tests",
                        "topology mismatches (collisions caught)", "texels outside their interval"},
                       {}};
  struct Subject {
    std::string name, file;
    bool heightfield;
  };
  for (const Subject& subject : {Subject{"nefertiti", "nefertiti/nefertiti.obj", false},
                                 Subject{"terragen", "terragen/RealisticTerrain.ter", true}}) {
    auto scene = context.shared_scene(subject.file, UpAxis::z, subject.heightfield);
    if (!scene) return scene.error();
    auto frame = LightFrame::fit(*light_direction_from_sun(135, 45, UpAxis::z), (*scene)->scene.bounds, resolution);
    if (!frame) return frame.error();
    auto layout = TileLayout::make(resolution, resolution);
    if (!layout) return layout.error();
    LightSpaceScene light_scene((*scene)->scene, *frame, *layout);
    DualDepthOptions depth_options;
    depth_options.exit_margin = float(frame->depth_from_world(4 * frame->texel_size()));
  depth_options.cap_exits_at_receiver_surfaces = true;
    DualDepthRenderer renderer(context.device(), light_scene, depth_options);
    auto tile = renderer.render({0, 0});
    if (!tile) return tile.error();
    auto mh = build_mh(*tile);
    if (!mh) return mh.error();
    for (unsigned bits : {1u, 2u, 4u, 8u, 64u}) {
      MmhMergeOptions options;
      options.hash_bits = bits;
      MmhMergeStats stats;
      auto merged = merge_mmh(*mh, options, &stats);
      if (!merged) return merged.error();
      auto payload = encode_mh(*merged);
      if (!payload) return payload.error();
      auto view = MhTileView::parse(*payload);
      if (!view) return view.error();
      MhVerifyReport report;
      Status exact = verify_lossless(*tile, *view, &report);
      table.rows.push_back({subject.name, std::to_string(bits), std::to_string(stats.blocks_before),
                            std::to_string(stats.blocks_after), std::to_string(stats.merges),
                            std::to_string(stats.full_tests), std::to_string(stats.topology_mismatches),
                            std::to_string(report.violations)});
      result.check(fmt::format("{} MMH with a {}-bit hash is exact", subject.name, bits),
                   exact.ok() && report.violations == 0,
                   fmt::format("{} of {} texels outside their interval", report.violations, report.texels));
      if (bits <= 2)
        result.check(fmt::format("{} {}-bit hash: collisions happened and were caught", subject.name, bits),
                     stats.topology_mismatches > 0,
                     fmt::format("{} topology mismatches in {} full tests", stats.topology_mismatches,
                                 stats.full_tests));
    }
  }
  result.tables.push_back(std::move(table));
  return result;
}

}  // namespace shadowtiles::bench
