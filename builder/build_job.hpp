// BuildJob: scene file -> store (docs/architecture.md §1). Loads and indexes the scene, fits the light frame,
// renders each non-empty tile's dual depth with Embree on `threads` workers, encodes every requested
// method and commits each tile (its blobs plus a progress mark) in one LMDB transaction.
//
// Resume: the store's meta holds a hash of everything that defines the output (scene bytes, light,
// resolution, tiling, methods, builder version). Rerunning the same build into the same store skips
// the committed tiles, so a killed build loses at most the tiles in flight. A store holding a
// different build is refused unless `overwrite` is set.
// Errors: invalid_input (bad scene or parameters, exit code 2 in the CLI), io_error / out_of_space
// (store), unsupported (method not implemented).
// Thread safety: run() uses its own worker threads; do not run two jobs on one store at once.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "builder/mh_builder.hpp"
#include "builder/scene_loader.hpp"
#include "builder/shard_plan.hpp"
#include "codec/light_frame.hpp"
#include "codec/receiver_contract.hpp"
#include "store/method.hpp"
#include "common/result.hpp"

namespace shadowtiles {

struct BuildConfig {
  std::filesystem::path scene_path;
  std::filesystem::path store_path;
  Vec3 light_direction{0, 0, -1};
  std::optional<uint32_t> resolution;   // one of resolution / texel_size
  std::optional<double> texel_size;
  uint32_t tile_size = 2048;  // the CLI's default (cli/command_build.cpp says why)
  unsigned threads = 2;
  std::vector<store::Method> methods{store::Method::raw};
  LoadOptions load;
  double bias_texels = 2.0;         // default query bias, in texel widths (stored in world units)
  double exit_margin_texels = 4.0;  // closed-mesh exits pulled back by this (>= the bias)
  // `surfaces` only: the entry rule's slack in texel widths (docs/receiver-contracts.md), at most the
  // bias (queries need a bias of at least the slack); 0 = off.
  double entry_slack_texels = 0.0;
  int zstd_level = 3;
  MhConstruction construction = MhConstruction::bottom_up;  // MH family: bottom-up or top-down
  uint64_t initial_map_size = 1ull << 30;
  bool overwrite = false;
  // Comparison only (stability suite): open surfaces exit at the far plane, the MMH authors' rule
  // that leaks light under open surfaces (DualDepthOptions::open_exit_at_far_plane).
  bool open_exit_at_far_plane = false;
  // Exits capped by every shadowed surface inside the texel (DualDepthOptions; on by default, off
  // with `build --no-exit-caps` for the papers' texel-centre intervals): receivers off the texel
  // centre (silhouettes, ridges at a grazing sun) never get more light than raw gives them. It costs
  // bytes where exits exist (stability suite, issue #8: nefertiti 2048^2 MH x1.6, terragen 1024^2
  // x2.2) and little build time since builder 0.3.0.
  bool cap_exits_at_receiver_surfaces = true;
  // Which receivers the intervals answer exactly (docs/receiver-contracts.md; `build --receivers`).
  ReceiverContract receivers = ReceiverContract::anywhere;
  // Under `anywhere`, accept nearly closed meshes as solids (builder/nearly_closed_meshes.hpp; `build
  // --no-nearly-closed` turns it off): their holes are patched for the exit counter, so their texels get
  // exits. On by default: a scan with a few holes is a solid to any user, and raw's answers are kept
  // (docs/receiver-contracts.md, "Nearly closed solids"). Ignored under `surfaces`, which needs no solids.
  bool close_nearly_closed = true;
  NearlyClosedOptions nearly_closed;
  // Scale-out (docs/scale-out.md): build only share `shard->index` of `shard->count` into this
  // store (a shard store for `shadowtiles merge`). The config hash stays the whole build's.
  std::optional<ShardSpec> shard;
  // Plan only: load and index the scene, put the plan for this many shards in the summary's stats
  // ("shard_plan", "imbalance") and return without touching any store.
  uint32_t plan_shards_only = 0;
  // Measurement (`build --tile-costs`): the printed summary lists each tile's measured cost
  // ("tile_costs": CPU and wall seconds, hit texels, blob bytes) or, with plan_shards_only, each tile's
  // planned work and its parts ("tile_work"), to fit and check the plan's work model.
  bool report_tile_costs = false;
  // Progress callback, called from the coordinating thread about once a second.
  std::function<void(const std::string& line)> on_progress;
  // Test hook: after this many tiles are committed, the process kills itself with SIGKILL.
  uint64_t debug_kill_after_tiles = 0;
};

struct BuildSummary {
  uint64_t tiles_total = 0;        // tiles in the map
  uint64_t tiles_candidate = 0;    // tiles some triangle projects onto
  uint64_t tiles_rendered = 0;     // rendered in this run (not resumed)
  uint64_t tiles_resumed = 0;      // already committed by an earlier run
  uint64_t tiles_stored = 0;       // non-empty tiles written in this run
  uint64_t rays = 0;
  uint64_t blob_bytes = 0;         // compressed bytes written in this run, all methods
  nlohmann::json to_json() const { return stats; }
  nlohmann::json stats;            // everything above plus seconds by phase and bytes by method
};

Result<BuildSummary> run_build(const BuildConfig& config);

}  // namespace shadowtiles
