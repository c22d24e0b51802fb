// `shadowtiles build SCENE --out STORE ...`: bake the sun's shadows of a scene into a store.
#include <cstdio>
#include <iostream>
#include <optional>

#include <spdlog/spdlog.h>

#include "builder/build_job.hpp"
#include "cli/batch_allocator.hpp"
#include "cli/cli_parsing.hpp"
#include "cli/commands.hpp"
#include "cli/exit_codes.hpp"

namespace shadowtiles::cli {
namespace {

struct BuildFlags {
  std::string scene, out, sun, light_dir, methods = "dagmh", up = "z", construction = "bottom-up", shard,
              receivers = "anywhere";
  uint32_t plan_shards = 0;
  uint32_t resolution = 0;
  double texel_size = 0;
  // 2048: against 4096 at 16384^2 a build of MH, MMH and DAG-MH took 0.60-0.99x the wall time and
  // 0.26-0.42x the peak memory (encoders and caps work in cache, the last tile idles a worker less);
  // MH/MMH bytes -5% to +1.4%, DAG-MH within 2.4% (docs/build-time.md, session 15).
  uint32_t tile = 2048;
  unsigned threads = 2;
  std::vector<std::string> heightfields;
  double bias_texels = 2.0, exit_margin_texels = 4.0;
  // Unset: the bias under `surfaces` (the entry rule on at the default query bias), 0 under `anywhere`.
  std::optional<double> entry_slack_texels;
  bool overwrite = false, json = false, exit_caps = true, tile_costs = false, nearly_closed = true;
  double nearly_closed_tolerance = 0.1;
  uint64_t kill_after = 0;
};

int run(const BuildFlags& flags) {
  BuildConfig config;
  config.scene_path = flags.scene;
  config.store_path = flags.out;
  auto up = parse_up_axis(flags.up);
  if (!up) { spdlog::error("{}", up.error().message); return kInvalidInput; }
  config.load.up = *up;
  config.load.heightfield_meshes = flags.heightfields;
  if (!flags.light_dir.empty()) {
    auto dir = parse_vec3(flags.light_dir, "--light-dir");
    if (!dir) { spdlog::error("{}", dir.error().message); return kInvalidInput; }
    config.light_direction = *dir;
  } else {
    auto sun = parse_numbers(flags.sun.empty() ? "135,45" : flags.sun, 2, "--sun");
    if (!sun) { spdlog::error("{}", sun.error().message); return kInvalidInput; }
    auto dir = light_direction_from_sun((*sun)[0], (*sun)[1], *up);
    if (!dir) { spdlog::error("{}", dir.error().message); return kInvalidInput; }
    config.light_direction = *dir;
  }
  if (flags.texel_size > 0) config.texel_size = flags.texel_size;
  else config.resolution = flags.resolution ? flags.resolution : 4096;
  config.tile_size = flags.tile;
  config.threads = flags.threads;
  auto methods = store::parse_method_list(flags.methods);
  if (!methods) { spdlog::error("--method: {}", methods.error().message); return kInvalidInput; }
  config.methods = *methods;
  if (flags.construction == "top-down") config.construction = MhConstruction::top_down;
  else if (flags.construction != "bottom-up") {
    spdlog::error("--mh-construction must be bottom-up or top-down");
    return kInvalidInput;
  }
  config.bias_texels = flags.bias_texels;
  config.exit_margin_texels = flags.exit_margin_texels;
  config.overwrite = flags.overwrite;
  config.cap_exits_at_receiver_surfaces = flags.exit_caps;
  config.close_nearly_closed = flags.nearly_closed;
  if (!(flags.nearly_closed_tolerance > 0 && flags.nearly_closed_tolerance < 0.5)) {
    spdlog::error("--nearly-closed-tolerance must be in (0, 0.5)");
    return kInvalidInput;
  }
  config.nearly_closed.tolerance = flags.nearly_closed_tolerance;
  auto receivers = parse_receiver_contract(flags.receivers);
  if (!receivers) { spdlog::error("--receivers must be anywhere or surfaces"); return kInvalidInput; }
  config.receivers = *receivers;
  config.entry_slack_texels =
      flags.entry_slack_texels.value_or(config.receivers == ReceiverContract::surfaces ? flags.bias_texels : 0.0);
  config.debug_kill_after_tiles = flags.kill_after;
  if (!flags.shard.empty()) {
    auto shard = parse_shard_spec(flags.shard);
    if (!shard) { spdlog::error("{}", shard.error().message); return kInvalidInput; }
    config.shard = *shard;
  }
  config.plan_shards_only = flags.plan_shards;
  config.report_tile_costs = flags.tile_costs;
  if (flags.out.empty() && !flags.plan_shards) { spdlog::error("--out is required"); return kInvalidInput; }
  config.on_progress = [](const std::string& line) { spdlog::info("{}", line); };
  keep_freed_memory_for_reuse();  // tile after tile, the same large buffers (cli/batch_allocator.hpp)

  auto summary = run_build(config);
  if (!summary) {
    spdlog::error("build failed ({}): {}", error_code_name(summary.error().code), summary.error().message);
    return exit_code_for(summary.error());
  }
  if (flags.json || flags.plan_shards) {
    std::cout << summary->stats.dump(2) << "\n";
  } else {
    const auto& s = summary->stats;
    std::printf("built %s -> %s\n", flags.scene.c_str(), flags.out.c_str());
    std::printf("  tiles: %llu total, %llu with triangles, %llu rendered now, %llu resumed, %llu stored\n",
                (unsigned long long)summary->tiles_total, (unsigned long long)summary->tiles_candidate,
                (unsigned long long)summary->tiles_rendered, (unsigned long long)summary->tiles_resumed,
                (unsigned long long)summary->tiles_stored);
    std::printf("  rays: %llu (%.2f Mrays/s)\n", (unsigned long long)summary->rays,
                s.value("rays_per_second", 0.0) / 1e6);
    if (s.contains("bytes_by_method"))
      for (auto& [method, bytes] : s["bytes_by_method"].items())
        std::printf("  bytes %-6s %llu\n", method.c_str(), (unsigned long long)bytes.get<uint64_t>());
    if (s.contains("seconds"))
      for (auto& [phase, seconds] : s["seconds"].items())
        std::printf("  seconds %-18s %.3f\n", phase.c_str(), seconds.get<double>());
    if (s.contains("wall_over_ray_casting"))
      std::printf("  build wall / ray casting wall %.2f\n", s["wall_over_ray_casting"].get<double>());
    if (s.contains("peak_memory_mib")) std::printf("  peak memory %.0f MiB\n", s["peak_memory_mib"].get<double>());
  }
  return kOk;
}

}  // namespace

void add_build_command(CLI::App& app, int& exit_code) {
  auto flags = std::make_shared<BuildFlags>();
  CLI::App* cmd = app.add_subcommand("build", "Bake a scene's sun shadows into a store");
  cmd->add_option("scene", flags->scene, "Scene file (OBJ, PLY, glTF/GLB, FBX, DAE, IFC, TER, ...)")->required();
  cmd->add_option("--out,-o", flags->out, "Store directory (LMDB) to write (required unless --plan-shards)");
  cmd->add_option("--shard", flags->shard,
                  "I/N: build only share I of N (balanced by work, contiguous in Morton order) into --out, "
                  "a local shard store for `shadowtiles merge` (docs/scale-out.md)");
  cmd->add_option("--plan-shards", flags->plan_shards,
                  "Print the work-balanced plan for N shards (JSON) and exit; builds nothing");
  cmd->add_flag("--tile-costs", flags->tile_costs,
                "With --json: list each tile's measured CPU seconds and its seconds by phase (with "
                "--plan-shards: its planned work and parts), to check the plan's work model");
  auto* sun = cmd->add_option("--sun", flags->sun, "Sun azimuth,elevation in degrees (default 135,45)");
  cmd->add_option("--light-dir", flags->light_dir, "Direction the light travels, X,Y,Z")->excludes(sun);
  cmd->add_option("--up", flags->up, "Scene up axis for --sun: z or y")->capture_default_str();
  auto* res = cmd->add_option("--resolution,-r", flags->resolution, "Shadow map texels per side (power of two <= 2^20)");
  cmd->add_option("--texel-size", flags->texel_size, "World size of a texel (picks the resolution)")->excludes(res);
  cmd->add_option("--tile", flags->tile, "Tile side in texels (power of two)")->capture_default_str();
  cmd->add_option("--threads,-j", flags->threads, "Worker threads")->capture_default_str();
  cmd->add_option("--method,-m", flags->methods, "Methods to store, comma-separated: raw, mh, mmh, dagmh, cpvs, sst (add raw for "
                  "comparisons and diffs)")->capture_default_str();
  cmd->add_option("--heightfield", flags->heightfields, "Mesh name solid below (terrain); '*' for all")
      ->take_all();
  cmd->add_option("--bias-texels", flags->bias_texels, "Default query bias in texel widths")->capture_default_str();
  cmd->add_option("--exit-margin-texels", flags->exit_margin_texels,
                  "Closed-mesh exits pulled back by this many texel widths (>= bias)")->capture_default_str();
  cmd->add_option("--entry-slack-texels", flags->entry_slack_texels,
                  "surfaces only: the entry rule (docs/receiver-contracts.md): MH, MMH, DAG-MH and CPVS values may "
                  "lie this many texel widths of depth above the first hit where a triangle covers the texel; "
                  "queries of those methods then need a bias of at least this (<= bias; 0: off; default: the "
                  "bias under surfaces, 0 under anywhere)");
  cmd->add_option("--mh-construction", flags->construction, "MH family: bottom-up or top-down (SBE16a Alg. 1)")
      ->capture_default_str();
  cmd->add_option("--receivers", flags->receivers,
                  "Receiver contract: anywhere (a query point may be anywhere outside closed solids) or surfaces "
                  "(query points lie on the scene's surfaces: any depth up to the second surface answers them, "
                  "so open meshes compress; docs/receiver-contracts.md)")
      ->capture_default_str();
  cmd->add_flag("--exit-caps,!--no-exit-caps", flags->exit_caps,
                "Exit caps (default on): cap each texel's upper bound by the shadowed surfaces inside its square, "
                "so receivers off the texel centre never get more light than raw gives them. --no-exit-caps "
                "stores the papers' texel-centre intervals (smaller where exits exist; leaks at silhouettes "
                "and ridges, STABILITY.md finding 1)");
  cmd->add_flag("--nearly-closed,!--no-nearly-closed", flags->nearly_closed,
                "Under --receivers anywhere (default on): accept meshes with a few holes or non-manifold edges "
                "as solids when their generalized winding number passes the test (tolerance below; each mesh's "
                "result is logged); their holes are patched for the exit counter, so the inside of the patched "
                "surface is no receiver place (docs/receiver-contracts.md)");
  cmd->add_option("--nearly-closed-tolerance", flags->nearly_closed_tolerance,
                  "Largest |w - w_patched| at the test's sample points, on all but 1% of a mesh's area")
      ->capture_default_str();
  cmd->add_flag("--overwrite", flags->overwrite, "Replace a different build in --out");
  cmd->add_flag("--json", flags->json, "Print the build summary as JSON");
  cmd->add_option("--debug-kill-after-tiles", flags->kill_after, "Test hook: SIGKILL self after N tiles")
      ->group("");
  cmd->callback([flags, &exit_code] { exit_code = run(*flags); });
}

}  // namespace shadowtiles::cli
