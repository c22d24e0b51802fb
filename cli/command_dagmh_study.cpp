// `shadowtiles dagmh-study SCENE --resolution R[,R...]`: the DAG-MH parameter study (issue #4,
// docs/architecture.md §7). For each resolution, renders one tile's dual depth at a time (the builder's
// renderer), builds its MH and MMH, encodes DAG-MH for every treelet height x chunk size and times
// random point and PCF 3x3 lookups on each; sizes and lookup counts are accumulated over the tiles,
// so a 64K^2 map never needs more than one tile in memory. Prints total payload bytes, DAG-MH/MMH
// and lookup rates per (height, chunk) and resolution (text or --json; add -q to keep progress
// lines out of stdout). Lookup rates: the fastest of three passes per tile. `--receivers` renders under
// either receiver contract (docs/receiver-contracts.md); the report also counts the MH's values by
// their interval's width (zero, under 8 exit margins, wider, misses), which is where DAG-MH's value
// bytes go (docs/dagmh.md, "Under the surfaces contract"). `--entry-slack-texels` studies the entry
// rule's lower bounds (docs/receiver-contracts.md, "The entry rule"), which builds do not use yet.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <optional>
#include <random>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "builder/build_job.hpp"
#include "builder/cpvs_encoder.hpp"
#include "builder/dagmh_encoder.hpp"
#include "builder/dagmh_sharing_study.hpp"
#include "builder/dual_depth_renderer.hpp"
#include "builder/embree_device.hpp"
#include "builder/light_space_scene.hpp"
#include "builder/mh_builder.hpp"
#include "builder/mh_encoder.hpp"
#include "builder/mmh_merger.hpp"
#include "builder/scene_loader.hpp"
#include "builder/second_layer_rule.hpp"
#include "cli/cli_parsing.hpp"
#include "cli/commands.hpp"
#include "cli/exit_codes.hpp"
#include "codec/dagmh_decoder.hpp"
#include "codec/light_frame.hpp"
#include "codec/mh_decoder.hpp"
#include "codec/tile_layout.hpp"

namespace shadowtiles::cli {
namespace {

using Clock = std::chrono::steady_clock;

struct StudyFlags {
  std::string scene, sun = "135,45", up = "z", receivers = "anywhere";
  std::vector<uint32_t> resolutions{16384};
  std::vector<std::string> heightfields;
  std::vector<unsigned> heights{2, 3, 4, 5}, chunks{16, 32, 64, 128};
  uint32_t tile = 4096;
  uint64_t sample_tiles = 0;   // 0: every non-empty tile
  unsigned lookups = 20000;    // per tile, per kind and parameter point
  double exit_margin_texels = 4.0;
  std::optional<double> entry_slack_texels;  // unset: as build (the default bias under surfaces)
  bool json = false;
};

// Lookups of one kind timed over tiles.
struct Rate {
  uint64_t lookups = 0;
  double seconds = 0;
  double per_second() const { return seconds > 0 ? double(lookups) / seconds : 0.0; }
};

struct PointTotals {
  uint64_t bytes = 0;
  Rate point, pcf3;
};

// Random texels and PCF boxes of one tile, the same for every method so rates compare.
struct Probes {
  std::vector<uint32_t> u, v;
};
Probes make_probes(uint32_t size, unsigned n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  Probes p;
  p.u.resize(n);
  p.v.resize(n);
  const uint32_t span = size >= 3 ? size - 2 : 1;  // 3x3 boxes stay inside the tile
  for (unsigned i = 0; i < n; ++i) p.u[i] = uint32_t(rng() % span), p.v[i] = uint32_t(rng() % span);
  return p;
}

// Each kind is timed `kRepeats` times and the fastest pass counts: on a shared machine the slower
// passes measure the other processes, not the decoder.
constexpr int kRepeats = 3;

template <class Fn>
double fastest_seconds(Fn&& pass) {
  double best = 1e300;
  for (int r = 0; r < kRepeats; ++r) {
    auto start = Clock::now();
    pass();
    best = std::min(best, std::chrono::duration<double>(Clock::now() - start).count());
  }
  return best;
}

template <class PointFn, class PcfFn>
void time_lookups(const Probes& probes, uint32_t size, PointFn&& point, PcfFn&& pcf, PointTotals& totals) {
  const unsigned k = size >= 3 ? 3 : 1;
  float sink = 0;
  uint64_t lit = 0;
  totals.point.seconds += fastest_seconds([&] {
    for (size_t i = 0; i < probes.u.size(); ++i) sink += point(probes.u[i], probes.v[i]);
  });
  totals.point.lookups += probes.u.size();
  totals.pcf3.seconds += fastest_seconds([&] {
    for (size_t i = 0; i < probes.u.size(); ++i) lit += pcf(probes.u[i], probes.v[i], k, 0.5f);
  });
  totals.pcf3.lookups += probes.u.size();
  // Keep the loops from being optimised away.
  if (lit == UINT64_MAX) std::printf("%f\n", sink);
}

struct ResolutionResult {
  uint32_t resolution = 0;
  uint64_t tiles = 0, tiles_nonempty = 0;
  uint64_t mh_bytes = 0;
  uint64_t cpvs_bytes = 0;  // the peer DAG-MH is compared with, from the same intervals
  PointTotals mmh;
  std::map<std::pair<unsigned, unsigned>, PointTotals> dag;
  DagMhSharingFigures sharing;  // one shape dictionary for all tiles, at the default treelet height
  // MH values by their interval's width: zero, narrow (< 8 exit margins), wide, misses (upper +inf).
  uint64_t values_zero = 0, values_narrow = 0, values_wide = 0, values_miss = 0;
  double seconds = 0;
};

Result<ResolutionResult> study_resolution(const StudyFlags& flags, const Scene& scene, const EmbreeDevice& device,
                                          const Vec3& light, uint32_t resolution) {
  auto start = Clock::now();
  auto frame = LightFrame::fit(light, scene.bounds, resolution);
  if (!frame) return frame.error();
  auto layout = TileLayout::make(resolution, std::min(flags.tile, resolution));
  if (!layout) return layout.error();
  LightSpaceScene light_scene(scene, *frame, *layout);
  // Rendered as the build job renders (same defaults), so sizes match a built store.
  const BuildConfig build_defaults;
  DualDepthOptions depth_options;
  depth_options.exit_margin = float(frame->depth_from_world(flags.exit_margin_texels * frame->texel_size()));
  depth_options.open_exit_at_far_plane = build_defaults.open_exit_at_far_plane;
  depth_options.cap_exits_at_receiver_surfaces = build_defaults.cap_exits_at_receiver_surfaces;
  depth_options.receivers = parse_receiver_contract(flags.receivers).value_or(ReceiverContract::anywhere);
  depth_options.coplanar_epsilon = float(
      second_layer::coplanar_epsilon(frame->depth_from_world(build_defaults.bias_texels * frame->texel_size())));
  const double entry_slack_texels = flags.entry_slack_texels.value_or(build_defaults.bias_texels);
  if (depth_options.receivers == ReceiverContract::surfaces && entry_slack_texels > 0) {
    depth_options.entry_slack = float(frame->depth_from_world(entry_slack_texels * frame->texel_size()));
    depth_options.entry_tolerance = float(entry_tolerance_depth(*frame, scene.bounds));
  }
  DualDepthRenderer renderer(device, light_scene, depth_options);

  std::vector<TileCoord> tiles;
  for (uint64_t i = 0; i < layout->tile_count(); ++i) {
    TileCoord tile = TileLayout::from_morton_index(i);
    if (!light_scene.triangles_of(tile).empty()) tiles.push_back(tile);
  }
  if (flags.sample_tiles > 0 && flags.sample_tiles < tiles.size()) {  // evenly spaced subset
    std::vector<TileCoord> picked;
    for (uint64_t k = 0; k < flags.sample_tiles; ++k) picked.push_back(tiles[k * tiles.size() / flags.sample_tiles]);
    tiles = std::move(picked);
  }

  ResolutionResult r;
  DagMhSharingStudy sharing(DagMhOptions{}.treelet_height);
  r.resolution = resolution;
  r.tiles = tiles.size();
  for (size_t t = 0; t < tiles.size(); ++t) {
    auto intervals = renderer.render(tiles[t]);
    if (!intervals) return intervals.error();
    if (intervals->all_missed()) continue;
    ++r.tiles_nonempty;
    apply_entry_rule(*intervals);  // (nothing without --entry-slack-texels)
    auto mh = build_mh(*intervals);
    if (!mh) return mh.error();
    auto mh_bytes = encode_mh(*mh);
    if (!mh_bytes) return mh_bytes.error();
    r.mh_bytes += mh_bytes->size();
    auto cpvs = encode_cpvs_tile(*intervals, resolution);
    if (!cpvs) return cpvs.error();
    r.cpvs_bytes += cpvs->size();
    auto classify = [&](const DepthInterval& iv) {
      if (!std::isfinite(iv.upper)) ++r.values_miss;
      else if (iv.upper == iv.lower) ++r.values_zero;
      else if (iv.upper - iv.lower < 8 * depth_options.exit_margin) ++r.values_narrow;
      else ++r.values_wide;
    };
    classify(mh->root);  // the root always has a value: DAG-MH's value list is the root, then these
    for (const DepthInterval& iv : mh->intervals) classify(iv);
    auto merged = merge_mmh(*mh);
    if (!merged) return merged.error();
    auto mmh_bytes = encode_mh(*merged);
    if (!mmh_bytes) return mmh_bytes.error();
    r.mmh.bytes += mmh_bytes->size();

    const uint32_t size = intervals->size;
    const Probes probes = make_probes(size, flags.lookups, 1000003ull * t + resolution);
    auto mmh_view = MhTileView::parse(*mmh_bytes);
    if (!mmh_view) return mmh_view.error();
    time_lookups(
        probes, size, [&](uint32_t u, uint32_t v) { return mmh_view->lookup(u, v); },
        [&](uint32_t u, uint32_t v, uint32_t k, float depth) { return mmh_view->pcf_lit_count(u, v, k, k, depth, 0.0f); },
        r.mmh);

    Status s = for_each_dagmh_parameter(
        *mh, flags.heights, flags.chunks, [&](unsigned height, unsigned chunk, std::span<const uint8_t> payload) -> Status {
          auto view = DagMhTileView::parse(payload);
          if (!view) return view.error();
          PointTotals& totals = r.dag[{height, chunk}];
          totals.bytes += payload.size();
          time_lookups(
              probes, size, [&](uint32_t u, uint32_t v) { return view->lookup(u, v); },
              [&](uint32_t u, uint32_t v, uint32_t k, float depth) { return view->pcf_lit_count(u, v, k, k, depth, 0.0f); },
              totals);
          return Status::success();
        });
    if (!s) return s.error();
    if (Status shared = sharing.add_tile(*mh); !shared) return shared.error();
    spdlog::info("{}^2: tile {}/{} ({},{}) done, {:.0f} s", resolution, t + 1, tiles.size(), tiles[t].x, tiles[t].y,
                 std::chrono::duration<double>(Clock::now() - start).count());
  }
  r.sharing = sharing.figures();
  r.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return r;
}

nlohmann::json to_json(const ResolutionResult& r) {
  nlohmann::json points = nlohmann::json::array();
  for (const auto& [key, t] : r.dag)
    points.push_back({{"treelet_height", key.first},
                      {"chunk_size", key.second},
                      {"bytes", t.bytes},
                      {"ratio_vs_mmh", r.mmh.bytes > 0 ? double(t.bytes) / double(r.mmh.bytes) : 0.0},
                      {"ratio_vs_cpvs", r.cpvs_bytes > 0 ? double(t.bytes) / double(r.cpvs_bytes) : 0.0},
                      {"point_random_per_second", t.point.per_second()},
                      {"pcf3_random_per_second", t.pcf3.per_second()}});
  return {{"resolution", r.resolution},
          {"tiles", r.tiles},
          {"tiles_nonempty", r.tiles_nonempty},
          {"mh_bytes", r.mh_bytes},
          {"cpvs_bytes", r.cpvs_bytes},
          {"mh_values",
           {{"zero_width", r.values_zero}, {"narrow", r.values_narrow}, {"wide", r.values_wide}, {"miss", r.values_miss}}},
          {"mmh_bytes", r.mmh.bytes},
          {"mmh_point_random_per_second", r.mmh.point.per_second()},
          {"mmh_pcf3_random_per_second", r.mmh.pcf3.per_second()},
          {"seconds", r.seconds},
          {"points", points},
          {"shared_dictionary",
           {{"treelet_height", DagMhOptions{}.treelet_height},
            {"per_tile_nodes", r.sharing.per_tile_nodes},
            {"per_tile_treelets", r.sharing.per_tile_treelets},
            {"per_tile_topology_bytes", r.sharing.per_tile_bytes},
            {"shared_nodes", r.sharing.shared_nodes},
            {"shared_treelets", r.sharing.shared_treelets},
            {"dictionary_bytes", r.sharing.dictionary_bytes},
            {"root_ref_bytes", r.sharing.root_ref_bytes},
            {"saving_bytes", int64_t(r.sharing.per_tile_bytes) - int64_t(r.sharing.shared_bytes())}}}};
}

void print_text(const ResolutionResult& r) {
  std::printf("%u^2: %llu tiles studied (%llu non-empty), %.0f s; MH %llu B, MMH %llu B, CPVS %llu B "
              "(MMH lookups: point %.2f M/s, PCF 3x3 %.2f M/s)\n",
              r.resolution, (unsigned long long)r.tiles, (unsigned long long)r.tiles_nonempty, r.seconds,
              (unsigned long long)r.mh_bytes, (unsigned long long)r.mmh.bytes, (unsigned long long)r.cpvs_bytes,
              r.mmh.point.per_second() / 1e6,
              r.mmh.pcf3.per_second() / 1e6);
  std::printf("MH values by interval width: zero %llu, narrow (< 8 exit margins) %llu, wide %llu, misses %llu\n",
              (unsigned long long)r.values_zero, (unsigned long long)r.values_narrow, (unsigned long long)r.values_wide,
              (unsigned long long)r.values_miss);
  std::printf("%7s %6s %14s %10s %10s %12s %12s\n", "height", "chunk", "bytes", "DAG/MMH", "DAG/CPVS", "point M/s",
              "pcf3 M/s");
  for (const auto& [key, t] : r.dag)
    std::printf("%7u %6u %14llu %10.4f %10.4f %12.2f %12.2f\n", key.first, key.second, (unsigned long long)t.bytes,
                r.mmh.bytes > 0 ? double(t.bytes) / double(r.mmh.bytes) : 0.0,
                r.cpvs_bytes > 0 ? double(t.bytes) / double(r.cpvs_bytes) : 0.0, t.point.per_second() / 1e6,
                t.pcf3.per_second() / 1e6);
  const DagMhSharingFigures& f = r.sharing;
  std::printf("shared shape dictionary (treelet height %u): per-tile topology %llu B (%llu nodes, %llu treelets); "
              "one dictionary %llu B (%llu nodes, %llu treelets) + %llu B root refs: saves %lld B\n",
              DagMhOptions{}.treelet_height, (unsigned long long)f.per_tile_bytes,
              (unsigned long long)f.per_tile_nodes, (unsigned long long)f.per_tile_treelets,
              (unsigned long long)f.dictionary_bytes, (unsigned long long)f.shared_nodes,
              (unsigned long long)f.shared_treelets, (unsigned long long)f.root_ref_bytes,
              (long long)f.per_tile_bytes - (long long)f.shared_bytes());
}

int run(const StudyFlags& flags) {
  auto up = parse_up_axis(flags.up);
  if (!up) { spdlog::error("{}", up.error().message); return kInvalidInput; }
  auto sun = parse_numbers(flags.sun, 2, "--sun");
  if (!sun) { spdlog::error("{}", sun.error().message); return kInvalidInput; }
  auto light = light_direction_from_sun((*sun)[0], (*sun)[1], *up);
  if (!light) { spdlog::error("{}", light.error().message); return kInvalidInput; }
  for (uint32_t resolution : flags.resolutions)
    if (resolution < 1 || (resolution & (resolution - 1)) != 0) {
      spdlog::error("--resolution: {} is not a power of two", resolution);
      return kInvalidInput;
    }
  for (unsigned height : flags.heights)
    for (unsigned chunk : flags.chunks)
      if (height < 2 || height > 5 || chunk < 1 || chunk > 1024) {
        spdlog::error("treelet heights must be 2..5 and chunk sizes 1..1024");
        return kInvalidInput;
      }
  if (!parse_receiver_contract(flags.receivers)) {
    spdlog::error("--receivers: '{}' is not anywhere or surfaces", flags.receivers);
    return kInvalidInput;
  }
  if (flags.heights.empty() || flags.chunks.empty() || flags.lookups == 0) {
    spdlog::error("need at least one height, one chunk size and one lookup");
    return kInvalidInput;
  }

  LoadOptions load;
  load.up = *up;
  load.heightfield_meshes = flags.heightfields;
  auto scene = load_scene(flags.scene, load);
  if (!scene) { spdlog::error("{}", scene.error().message); return exit_code_for(scene.error()); }
  auto device = EmbreeDevice::create();
  if (!device) { spdlog::error("{}", device.error().message); return exit_code_for(device.error()); }

  nlohmann::json report = {{"scene", flags.scene}, {"resolutions", nlohmann::json::array()}};
  for (uint32_t resolution : flags.resolutions) {
    auto result = study_resolution(flags, *scene, *device, *light, resolution);
    if (!result) { spdlog::error("{}", result.error().message); return exit_code_for(result.error()); }
    if (flags.json) report["resolutions"].push_back(to_json(*result));
    else print_text(*result);
    std::fflush(stdout);
  }
  if (flags.json) std::cout << report.dump(2) << "\n";
  return kOk;
}

}  // namespace

void add_dagmh_study_command(CLI::App& app, int& exit_code) {
  auto flags = std::make_shared<StudyFlags>();
  CLI::App* cmd = app.add_subcommand("dagmh-study", "DAG-MH parameter study: treelet height x chunk size (issue #4)");
  cmd->add_option("scene", flags->scene, "Scene file")->required();
  cmd->add_option("--resolution,-r", flags->resolutions, "Map resolutions, comma-separated (e.g. 16384,65536)")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--sun", flags->sun, "Sun azimuth,elevation in degrees")->capture_default_str();
  cmd->add_option("--up", flags->up, "Scene up axis: z or y")->capture_default_str();
  cmd->add_option("--heightfield", flags->heightfields, "Mesh name solid below (terrain); '*' for all")
      ->delimiter(',');
  cmd->add_option("--tile", flags->tile, "Tile side in texels")->capture_default_str();
  cmd->add_option("--heights", flags->heights, "Treelet heights (2..5)")->delimiter(',')->capture_default_str();
  cmd->add_option("--chunks", flags->chunks, "Chunk sizes (1..1024)")->delimiter(',')->capture_default_str();
  cmd->add_option("--lookups", flags->lookups, "Random lookups per tile, kind and parameter point")
      ->capture_default_str();
  cmd->add_option("--sample-tiles", flags->sample_tiles, "Study only this many evenly spaced non-empty tiles (0: all)")
      ->capture_default_str();
  cmd->add_option("--exit-margin-texels", flags->exit_margin_texels, "As for build")->capture_default_str();
  cmd->add_option("--receivers", flags->receivers, "Receiver contract, as for build: anywhere or surfaces")
      ->capture_default_str();
  cmd->add_option("--entry-slack-texels", flags->entry_slack_texels,
                  "surfaces only: study the entry rule for query biases of at least this many texels "
                  "(docs/receiver-contracts.md; 0: off; default: as build, the default bias under surfaces)")
      ->check(CLI::Range(0.0, 64.0));
  cmd->add_flag("--json", flags->json, "Print JSON");
  cmd->callback([flags, &exit_code] { exit_code = run(*flags); });
}

}  // namespace shadowtiles::cli
