#include "builder/build_job.hpp"

#include <sys/resource.h>
#include <xxhash.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <cstdio>
#include <map>
#include <memory>

#include <spdlog/spdlog.h>

#include "builder/builder_version.hpp"
#include "builder/dual_depth_renderer.hpp"
#include "builder/file_hash.hpp"
#include "builder/light_space_scene.hpp"
#include "builder/second_layer_rule.hpp"
#include "builder/tile_pipeline.hpp"
#include "builder/tile_coverage_estimate.hpp"
#include "builder/top_levels.hpp"
#include "codec/store_meta.hpp"
#include "store/lmdb_store.hpp"
#include "store/serving_lock.hpp"
#include "store/store_layout.hpp"

namespace shadowtiles {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

std::string hex64(uint64_t value) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(value));
  return text;
}

std::vector<uint8_t> bytes_of(std::string_view text) { return {text.begin(), text.end()}; }

double peak_memory_mib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_maxrss) / 1024.0;
}

Status validate(const BuildConfig& config) {
  if (config.threads < 1 || config.threads > 256)
    return make_error(ErrorCode::invalid_input, "threads must be in [1, 256]");
  if (config.methods.empty()) return make_error(ErrorCode::invalid_input, "no method requested");
  for (store::Method method : config.methods)
    if (!builder_supports(method))
      return make_error(ErrorCode::unsupported,
                        std::string("method '") + store::method_name(method) + "' is not implemented yet");
  if (config.resolution.has_value() == config.texel_size.has_value())
    return make_error(ErrorCode::invalid_input, "give exactly one of resolution and texel size");
  if (!(config.bias_texels >= 0) || !(config.exit_margin_texels >= config.bias_texels))
    return make_error(ErrorCode::invalid_input, "need 0 <= bias <= exit margin (in texels)");
  if (!(config.entry_slack_texels >= 0) || config.entry_slack_texels > config.bias_texels)
    return make_error(ErrorCode::invalid_input, "need 0 <= entry slack <= bias (in texels)");
  if (config.entry_slack_texels > 0 && config.receivers != ReceiverContract::surfaces)
    return make_error(ErrorCode::invalid_input, "the entry slack needs --receivers surfaces");
  if (config.store_path.empty() && !config.plan_shards_only)
    return make_error(ErrorCode::invalid_input, "no output store given");
  return {};
}

// Nearly closed meshes are solids only under `anywhere` (BuildConfig::close_nearly_closed).
bool closes_nearly_closed(const BuildConfig& config) {
  return config.close_nearly_closed && config.receivers == ReceiverContract::anywhere;
}

// Everything that defines the stored bytes: a store built from a different identity is not resumed.
nlohmann::json build_identity(const BuildConfig& config, uint64_t scene_hash, uint32_t resolution,
                              uint32_t tile_size) {
  nlohmann::json methods = nlohmann::json::array();
  for (store::Method m : config.methods) methods.push_back(store::method_name(m));
  nlohmann::json identity = {{"builder", builder_version()},
          {"store_format", kStoreFormatVersion},
          {"scene_xxh64", hex64(scene_hash)},
          {"light", {config.light_direction[0], config.light_direction[1], config.light_direction[2]}},
          {"resolution", resolution},
          {"tile_size", tile_size},
          {"methods", methods},
          {"heightfield", config.load.heightfield_meshes},
          {"bias_texels", config.bias_texels},
          {"exit_margin_texels", config.exit_margin_texels},
          {"zstd_level", config.zstd_level},
          {"construction", config.construction == MhConstruction::top_down ? "top_down" : "bottom_up"}};
  // Only when set, so stores built before the option existed keep their identity.
  if (config.open_exit_at_far_plane) identity["open_exit_at_far_plane"] = true;
  if (config.cap_exits_at_receiver_surfaces) identity["exit_caps"] = "receiver_surfaces";
  if (config.receivers != ReceiverContract::anywhere) identity["receivers"] = receiver_contract_name(config.receivers);
  if (config.entry_slack_texels > 0) identity["entry_slack_texels"] = config.entry_slack_texels;
  if (closes_nearly_closed(config))
    identity["nearly_closed"] = {{"tolerance", config.nearly_closed.tolerance},
                                 {"max_ambiguous_area", config.nearly_closed.max_ambiguous_area},
                                 {"max_samples", config.nearly_closed.max_samples},
                                 {"max_patch_triangles", config.nearly_closed.max_patch_triangles},
                                 {"min_full_samples", config.nearly_closed.min_full_samples},
                                 {"full_budget", config.nearly_closed.full_budget},
                                 {"max_misplaced_area", config.nearly_closed.max_misplaced_area}};
  return identity;
}

// One line when most triangles are one-sided under the `anywhere` contract: their texels get
// zero-width intervals, which the MH family cannot compress.
void log_open_mesh_hint(const Scene& scene, ReceiverContract receivers) {
  if (receivers != ReceiverContract::anywhere) return;  // surfaces already widens them
  uint64_t open = 0;
  for (const MeshInfo& mesh : scene.meshes)
    if (mesh.kind == MeshKind::open) open += mesh.triangle_count;
  if (scene.triangle_count() == 0 || 2 * open <= scene.triangle_count()) return;
  spdlog::warn("{:.0f}% of the triangles are in open meshes: under --receivers anywhere their texels have "
               "interval width 0 (MH/MMH/DAG-MH gain little there); --receivers surfaces (receivers on the "
               "scene's surfaces) widens them to the second surface",
               100.0 * double(open) / double(scene.triangle_count()));
}

// Work of every tile with triangles, in Morton order (builder/shard_plan.hpp).
std::vector<TileWork> candidate_work(const LightSpaceScene& light_scene, const TileLayout& layout) {
  std::vector<TileWork> work;
  for (uint64_t i = 0; i < layout.tile_count(); ++i) {
    TileCoord tile = TileLayout::from_morton_index(i);
    size_t refs = light_scene.triangles_of(tile).size();
    if (!refs) continue;
    const TileFootprint f = estimate_tile_footprint(light_scene, tile);
    work.push_back({i, uint64_t(layout.tile_size()) * layout.tile_size(), refs, f.covered_texels, f.triangle_edges,
                    f.visible_triangles, f.sub_cell_triangles, f.plane_edges, f.layered_cells});
  }
  return work;
}

uint64_t covered_texels_estimate(const std::vector<TileWork>& work) {
  uint64_t sum = 0;
  for (const TileWork& w : work) sum += w.covered_texels;
  return sum;
}

nlohmann::json plan_json(const std::vector<ShardRange>& plan) {
  nlohmann::json shards = nlohmann::json::array();
  for (const ShardRange& r : plan)
    shards.push_back({{"morton_begin", r.morton_begin}, {"morton_end", r.morton_end}, {"tiles", r.tiles}, {"work", r.work}});
  return shards;
}

// The cap pass's counts summed over this run's tiles (pairs and regions are `surfaces`' only).
nlohmann::json cap_pass_json(const SecondLayerCapCounts& caps) {
  const ReceiverCapCounts& t = caps.texels;
  return {{"pairs_tested", caps.pairs_tested}, {"regions", caps.regions}, {"near_regions", caps.near_regions},
          {"skipped", caps.skipped}, {"triangles_without_capped_texels", t.triangles_skipped},
          {"texels", {{"clipped", t.clipped}, {"interior", t.interior}, {"fallback", t.fallback},
                      {"already_lower", t.already_lower}, {"corner", t.corner}, {"chord", t.chord}}}};
}

std::string shard_name(const std::optional<ShardInfo>& shard) {
  return shard ? "shard " + std::to_string(shard->index) + "/" + std::to_string(shard->count) : "a whole build";
}

// ---- Phases of run_build (docs/architecture.md §9) ----

// Phase 1, prepare: what the scene and the config define (no store touched yet).
struct PreparedBuild {
  Scene scene;
  LoadStats load_stats;
  LightFrame frame;
  TileLayout layout;
  std::string config_hash;
};

Result<PreparedBuild> prepare(const BuildConfig& config) {
  LoadStats load_stats;
  LoadOptions load = config.load;
  load.close_nearly_closed = closes_nearly_closed(config);
  load.nearly_closed = config.nearly_closed;
  load.nearly_closed.threads = config.threads;  // the workers are idle while the scene loads
  auto scene = load_scene(config.scene_path, load, &load_stats);
  if (!scene) return scene.error();
  uint32_t resolution = 0;
  if (config.resolution) {
    resolution = *config.resolution;
  } else {
    auto fitted = LightFrame::resolution_for_texel_size(config.light_direction, scene->bounds, *config.texel_size);
    if (!fitted) return fitted.error();
    resolution = *fitted;
  }
  // The far margin keeps every surface well short of depth 1 for any bias up to the exit margin, so
  // receivers beyond the far plane can be answered as if on it (see LightFrame::fit).
  auto frame = LightFrame::fit(config.light_direction, scene->bounds, resolution,
                               std::max(LightFrame::kDefaultFarMarginTexels, 4 * config.exit_margin_texels));
  if (!frame) return frame.error();
  auto layout = TileLayout::make(resolution, config.tile_size);
  if (!layout) return layout.error();
  spdlog::info("light frame: {}^2 texels of {:.6g} world units, {}^2 tiles of {}^2, depth range {:.6g}",
               resolution, frame->texel_size(), layout->tiles_per_side(), layout->tile_size(), frame->depth_range());
  log_open_mesh_hint(*scene, config.receivers);
  auto scene_hash = hash_file(config.scene_path);
  if (!scene_hash) return scene_hash.error();
  const std::string identity = build_identity(config, *scene_hash, resolution, layout->tile_size()).dump();
  return PreparedBuild{std::move(*scene), load_stats, *frame, *layout,
                       hex64(XXH64(identity.data(), identity.size(), 0))};
}

// --plan-shards N: the shard plan only, nothing built.
BuildSummary plan_only(const BuildConfig& config, const PreparedBuild& build) {
  LightSpaceScene light_scene(build.scene, build.frame, build.layout);
  auto work = candidate_work(light_scene, build.layout);
  auto plan = plan_shards(work, build.layout.tile_count(), config.plan_shards_only);
  BuildSummary summary;
  summary.tiles_total = build.layout.tile_count();
  summary.tiles_candidate = work.size();
  summary.stats = {{"config_hash", build.config_hash},
                   {"tiles", {{"total", summary.tiles_total}, {"with_triangles", work.size()}}},
                   {"triangle_references", light_scene.triangle_references()},
                   {"covered_texels_estimate", covered_texels_estimate(work)},
                   {"shard_plan", plan_json(plan)},
                   {"imbalance", shard_imbalance(plan)}};
  if (config.report_tile_costs) {
    nlohmann::json tiles = nlohmann::json::array();
    for (const TileWork& w : work)
      tiles.push_back({{"morton", w.morton_index}, {"triangle_refs", w.triangle_refs}, {"covered_texels", w.covered_texels},
                       {"triangle_edges", w.triangle_edges}, {"visible_triangles", w.visible_triangles},
                       {"sub_cell_triangles", w.sub_cell_triangles}, {"plane_edges", w.plane_edges},
                       {"layered_cells", w.layered_cells}, {"work", w.work()}});
    summary.stats["tile_work"] = std::move(tiles);
  }
  return summary;
}

// Phase 2, open/resume: the store, locked against servers; a different build is refused (or cleared
// with --overwrite), the same build (and the same share of it) is resumed.
struct OpenedStore {
  std::unique_ptr<store::Store> db;
  store::ServingLock serving_lock;  // held until the build ends (store/serving_lock.hpp)
  bool had_meta = false;
};

Result<OpenedStore> open_or_resume(const BuildConfig& config, const std::string& config_hash) {
  store::Store::Options store_options;
  store_options.mode = store::Store::Mode::read_write;
  store_options.initial_map_size = config.initial_map_size;
  store_options.no_sync = true;  // one forced sync at the end (docs/architecture.md §9)
  auto opened = store::Store::open(config.store_path, store_options);
  if (!opened) return opened.error();
  auto serving_lock = store::ServingLock::acquire(config.store_path, store::ServingLock::Kind::build);
  if (!serving_lock) return serving_lock.error();
  store::Store& db = **opened;
  auto existing = db.get(store::Database::meta, store::as_bytes(kMetaBuildKey));
  if (!existing) return existing.error();
  const bool had_meta = existing->has_value();
  if (had_meta) {
    auto old_meta = StoreMeta::parse(std::string_view(reinterpret_cast<const char*>((*existing)->data()),
                                                      (*existing)->size()));
    bool same = old_meta && old_meta->config_hash == config_hash;
    // A shard resumes only its own share of the same build.
    bool same_share = old_meta && old_meta->shard.has_value() == config.shard.has_value() &&
                      (!config.shard || (old_meta->shard->index == config.shard->index &&
                                         old_meta->shard->count == config.shard->count));
    if (same && !same_share && !config.overwrite)
      return make_error(ErrorCode::invalid_input,
                        "store " + config.store_path.string() + " holds " + shard_name(old_meta->shard) +
                            " of this build, not " +
                            (config.shard ? "shard " + std::to_string(config.shard->index) + "/" +
                                                std::to_string(config.shard->count)
                                          : std::string("a whole build")) +
                            "; pass --overwrite or choose another --out");
    same = same && same_share;
    if (!same) {
      if (!config.overwrite)
        return make_error(ErrorCode::invalid_input,
                          "store " + config.store_path.string() +
                              " holds a different build; pass --overwrite or choose another --out");
      spdlog::warn("overwriting the build in {}", config.store_path.string());
      for (auto which : {store::Database::meta, store::Database::tiles, store::Database::top,
                         store::Database::progress, store::Database::preview, store::Database::tileinfo})
        if (Status s = db.clear(which); !s) return s.error();
    }
  }
  return OpenedStore{std::move(*opened), std::move(*serving_lock), had_meta};
}

StoreMeta initial_meta(const BuildConfig& config, const PreparedBuild& build) {
  StoreMeta meta;
  meta.builder_version = builder_version();
  meta.config_hash = build.config_hash;
  meta.scene_path = config.scene_path.string();
  meta.scene_triangles = build.scene.triangle_count();
  meta.up_axis = config.load.up == UpAxis::y ? "y" : "z";
  meta.heightfield_meshes = config.load.heightfield_meshes;
  meta.scene_bounds = build.scene.bounds;
  meta.light_direction = build.frame.direction();
  meta.light_origin = build.frame.origin();
  meta.light_extent = build.frame.extent();
  meta.light_depth_range = build.frame.depth_range();
  meta.resolution = build.layout.resolution();
  meta.tile_size = build.layout.tile_size();
  meta.methods = config.methods;
  meta.default_bias = config.bias_texels * build.frame.texel_size();
  meta.exit_margin = config.exit_margin_texels * build.frame.texel_size();
  meta.receivers = config.receivers;
  meta.exit_caps = config.cap_exits_at_receiver_surfaces && !config.open_exit_at_far_plane;
  meta.entry_slack = config.entry_slack_texels * build.frame.texel_size();
  meta.nearly_closed = closes_nearly_closed(config);
  if (meta.nearly_closed) {
    meta.nearly_closed_tolerance = config.nearly_closed.tolerance;
    meta.nearly_closed_max_ambiguous_area = config.nearly_closed.max_ambiguous_area;
    meta.nearly_closed_max_samples = config.nearly_closed.max_samples;
    meta.nearly_closed_max_patch_triangles = config.nearly_closed.max_patch_triangles;
    meta.nearly_closed_min_full_samples = config.nearly_closed.min_full_samples;
    meta.nearly_closed_full_budget = config.nearly_closed.full_budget;
    meta.nearly_closed_max_misplaced_area = config.nearly_closed.max_misplaced_area;
  }
  return meta;
}

// Phase 3, index: which tiles have triangles (in this shard's share), which are committed already.
struct TileIndex {
  std::map<TileCoord, DepthInterval> done;  // committed tiles and their root intervals
  std::vector<TileCoord> todo;
  uint64_t candidates = 0;
  double seconds = 0;
};

Result<TileIndex> index_tiles(const BuildConfig& config, const LightSpaceScene& light_scene,
                              const TileLayout& layout, store::Store& db, StoreMeta& meta) {
  auto start = Clock::now();
  TileIndex index;
  Status bad_progress;  // a corrupt record is an error, never a guess at what was done
  if (Status s = db.for_each(store::Database::progress, {},
                             [&](std::span<const uint8_t> key, std::span<const uint8_t> value) {
                               auto tile = store::decode_progress_key(key);
                               auto record = store::decode_progress(value);
                               if (!tile || !record) {
                                 bad_progress = tile ? record.error() : tile.error();
                                 return false;
                               }
                               index.done[TileCoord{tile->x, tile->y}] = {record->root_lower, record->root_upper};
                               return true;
                             });
      !s)
    return s.error();
  if (!bad_progress) return bad_progress.error();
  std::vector<TileWork> work = candidate_work(light_scene, layout);
  uint64_t share_begin = 0, share_end = layout.tile_count();
  if (config.shard) {
    auto plan = plan_shards(work, layout.tile_count(), config.shard->count);
    const ShardRange& mine = plan[config.shard->index];
    share_begin = mine.morton_begin;
    share_end = mine.morton_end;
    meta.shard = ShardInfo{config.shard->index, config.shard->count, mine.morton_begin, mine.morton_end,
                           mine.tiles, mine.work, false, config.zstd_level};
    spdlog::info("shard {}/{}: Morton tiles [{}, {}), {} tiles with triangles, work {:.3g} (imbalance of the plan {:.3f})",
                 config.shard->index, config.shard->count, share_begin, share_end, mine.tiles, mine.work,
                 shard_imbalance(plan));
  }
  std::vector<const TileWork*> todo_work;
  for (const TileWork& w : work) {
    if (w.morton_index < share_begin || w.morton_index >= share_end) continue;
    TileCoord tile = TileLayout::from_morton_index(w.morton_index);
    ++index.candidates;
    if (!index.done.count(tile)) todo_work.push_back(&w);
  }
  // Largest estimated work first, so the last tiles are small ones and no worker idles while another
  // finishes a big tile (the tiles' blobs do not depend on the order they are built in).
  std::stable_sort(todo_work.begin(), todo_work.end(),
                   [](const TileWork* a, const TileWork* b) { return a->work() > b->work(); });
  for (const TileWork* w : todo_work) index.todo.push_back(TileLayout::from_morton_index(w->morton_index));
  index.seconds = seconds_since(start);
  spdlog::info("{} of {} tiles have triangles ({} triangle references); {} already committed, {} to render",
               index.candidates, layout.tile_count(), light_scene.triangle_references(),
               index.candidates - index.todo.size(), index.todo.size());
  return index;
}

Status write_meta(store::Store& db, const StoreMeta& meta) {
  std::string text = meta.to_json().dump();
  std::vector<store::Store::Put> puts{{store::Database::meta, bytes_of(kMetaBuildKey), bytes_of(text)}};
  return db.write(puts);
}

DualDepthOptions depth_options_for(const BuildConfig& config, const LightFrame& frame, const StoreMeta& meta) {
  DualDepthOptions options;
  options.exit_margin = float(frame.depth_from_world(meta.exit_margin));
  options.open_exit_at_far_plane = config.open_exit_at_far_plane;
  options.cap_exits_at_receiver_surfaces = config.cap_exits_at_receiver_surfaces;
  options.receivers = config.receivers;
  options.coplanar_epsilon = float(second_layer::coplanar_epsilon(frame.depth_from_world(meta.default_bias)));
  options.entry_slack = float(frame.depth_from_world(meta.entry_slack));
  options.entry_tolerance = float(entry_tolerance_depth(frame, meta.scene_bounds));
  return options;
}

// Phase 5, top levels: the tiles' root intervals form a coarse map, itself compressed as an MH per
// hierarchical method, with the skip list embedded (served as /v1/skiplist). A shard holds only some
// roots, so the merge builds its top levels instead. Returns the top blobs' bytes per method.
Result<nlohmann::json> write_top_levels(const BuildConfig& config, const TileLayout& layout,
                                        const std::map<TileCoord, DepthInterval>& roots, store::Store& db) {
  nlohmann::json top_bytes = nlohmann::json::object();
  if (config.shard) return top_bytes;
  std::vector<DepthInterval> grid(size_t(layout.tiles_per_side()) * layout.tiles_per_side());
  for (const auto& [tile, root] : roots) grid[size_t(tile.y) * layout.tiles_per_side() + tile.x] = root;
  auto tops = encode_top_levels(config.methods, layout.tiles_per_side(), std::move(grid), layout.tile_level(),
                                config.zstd_level);
  if (!tops) return tops.error();
  std::vector<store::Store::Put> puts;
  for (TopLevelBlob& top : *tops) {
    top_bytes[store::method_name(top.method)] = top.blob.size();
    puts.push_back({store::Database::top, bytes_of(top_tree_key(top.method)), std::move(top.blob)});
  }
  if (!puts.empty())
    if (Status s = db.write(puts); !s) return s.error();
  return top_bytes;
}

// The build's figures (BuildSummary::stats, also kept in the meta).
struct PhaseTimes {
  double index = 0, render_wall = 0, top_levels = 0;
};

BuildSummary summarize(const PreparedBuild& build, const TileIndex& index, const TilePipelineResult& tiles,
                       const nlohmann::json& top_bytes, const PhaseTimes& times, Clock::time_point total_start) {
  const TilePipelineTotals& totals = tiles.totals;
  // Ray casting wall: the dual-depth casting alone (BVH + rays, not the cap pass, encoders or store)
  // spread over the worker threads, i.e. what the build would take if it only cast rays.
  const double ray_casting_wall =
      tiles.threads ? (totals.depth.bvh_seconds + totals.depth.ray_seconds) / double(tiles.threads) : 0.0;
  BuildSummary summary;
  summary.tiles_total = build.layout.tile_count();
  summary.tiles_candidate = index.candidates;
  summary.tiles_rendered = index.todo.size();
  summary.tiles_resumed = index.candidates - index.todo.size();
  summary.tiles_stored = totals.stored_tiles;
  summary.rays = totals.depth.rays;
  summary.blob_bytes = totals.blob_bytes;
  nlohmann::json bytes = totals.bytes_by_method, raw_bytes = totals.raw_bytes_by_method;
  summary.stats = {
      {"tiles", {{"total", summary.tiles_total}, {"with_triangles", index.candidates},
                 {"rendered", summary.tiles_rendered}, {"resumed", summary.tiles_resumed},
                 {"stored", summary.tiles_stored}}},
      {"scene", {{"triangles", build.scene.triangle_count()}, {"dropped", build.load_stats.dropped_triangles},
                 {"meshes", build.load_stats.meshes}, {"closed_meshes", build.load_stats.closed_meshes},
                 {"nearly_closed", {{"meshes", build.load_stats.nearly_closed.accepted_meshes},
                                    {"triangles", build.load_stats.nearly_closed.accepted_triangles},
                                    {"patch_triangles", build.load_stats.nearly_closed.patch_triangles},
                                    {"tested", build.load_stats.nearly_closed.meshes.size()}}}}},
      {"rays", summary.rays},
      {"hit_texels", totals.depth.hits},   // texels some geometry covers (this run's tiles)
      {"exit_texels", totals.depth.exits}, // texels with a real exit (upper > lower)
      // The cap pass's work (builder/second_layer_caps.hpp): where its time goes (docs/build-time.md).
      {"caps", cap_pass_json(totals.depth.caps)},
      {"rays_per_second", times.render_wall > 0 ? double(summary.rays) / times.render_wall : 0.0},
      // Ray casting alone (BVH build excluded), per worker thread.
      {"rays_per_thread_second",
       totals.depth.ray_seconds > 0 ? double(summary.rays) / totals.depth.ray_seconds : 0.0},
      {"threads", tiles.threads},
      {"seconds", {{"load", build.load_stats.seconds}, {"index", times.index},
                   {"bvh_thread_sum", totals.depth.bvh_seconds}, {"rays_thread_sum", totals.depth.ray_seconds},
                   {"caps_thread_sum", totals.depth.cap_seconds}, {"entry_rule_thread_sum", totals.depth.entry_seconds},
                   {"ray_casting_wall", ray_casting_wall},
                   {"encode_thread_sum", totals.encode_seconds},
                   {"preview_thread_sum", totals.preview_seconds}, {"store_thread_sum", totals.store_seconds},
                   {"render_wall", times.render_wall}, {"top_levels", times.top_levels},
                   {"total", seconds_since(total_start)}}},
      {"bytes_by_method", bytes},
      {"top_bytes_by_method", top_bytes},
      {"preview_bytes", totals.preview_bytes},
      {"reference_bytes_by_method", totals.reference_bytes_by_method},
      {"encode_seconds_by_method", totals.encode_seconds_by_method},
      {"payload_bytes_by_method", raw_bytes},
      {"peak_memory_mib", peak_memory_mib()},
  };
  return summary;
}

// Phase 6, finish: the meta marked complete (a shard: its share complete) with the stats, then one
// forced sync; the build-time ratio of issue 14.
Status finish(store::Store& db, StoreMeta& meta, BuildSummary& summary, Clock::time_point total_start) {
  if (meta.shard) {
    meta.shard->complete = true;  // the share is done; the whole build is complete once merged
    summary.stats["shard"] = {{"index", meta.shard->index}, {"count", meta.shard->count},
                              {"morton_begin", meta.shard->morton_begin}, {"morton_end", meta.shard->morton_end},
                              {"work", meta.shard->work}};
  } else {
    meta.complete = true;
  }
  meta.build_stats = summary.stats;
  if (Status s = write_meta(db, meta); !s) return s;
  if (Status s = db.sync(); !s) return s;
  summary.stats["seconds"]["total"] = seconds_since(total_start);
  // Build wall over ray-casting wall (issue 14's build-time figure); with the meta's own total.
  const double ray_casting_wall = summary.stats["seconds"]["ray_casting_wall"].get<double>();
  if (ray_casting_wall > 0)
    summary.stats["wall_over_ray_casting"] = summary.stats["seconds"]["total"].get<double>() / ray_casting_wall;
  return {};
}

}  // namespace

Result<BuildSummary> run_build(const BuildConfig& config) {
  const auto total_start = Clock::now();
  if (Status status = validate(config); !status) return status.error();
  if (config.shard && config.plan_shards_only)
    return make_error(ErrorCode::invalid_input, "give --shard or --plan-shards, not both");

  // 1. Prepare: scene, light frame, tile layout, the build's identity.
  auto build = prepare(config);
  if (!build) return build.error();
  if (config.plan_shards_only) return plan_only(config, *build);

  // 2. Open or resume the store.
  auto opened = open_or_resume(config, build->config_hash);
  if (!opened) return opened.error();
  store::Store& db = *opened->db;
  StoreMeta meta = initial_meta(config, *build);

  // 3. Index: tiles with triangles in this share, minus those committed already.
  LightSpaceScene light_scene(build->scene, build->frame, build->layout);
  auto index = index_tiles(config, light_scene, build->layout, db, meta);
  if (!index) return index.error();
  if (!opened->had_meta || !index->todo.empty() || !index->done.empty())
    if (Status s = write_meta(db, meta); !s) return s.error();

  // 4. Render + encode + commit every tile to do (builder/tile_pipeline.hpp).
  auto device = EmbreeDevice::create();
  if (!device) return device.error();
  DualDepthRenderer renderer(*device, light_scene, depth_options_for(config, build->frame, meta));
  TilePipelineInput pipeline;
  pipeline.methods = &config.methods;
  pipeline.layout = &build->layout;
  pipeline.renderer = &renderer;
  pipeline.encode_options.construction = config.construction;
  pipeline.encode_options.map_resolution = build->layout.resolution();
  pipeline.zstd_level = config.zstd_level;
  pipeline.threads = config.threads;
  pipeline.debug_kill_after_tiles = config.debug_kill_after_tiles;
  pipeline.on_progress = config.on_progress;
  auto tiles = run_tile_pipeline(pipeline, index->todo, db);
  if (!tiles) return tiles.error();

  // 5. Top levels from every tile's root, resumed ones included.
  auto top_start = Clock::now();
  std::map<TileCoord, DepthInterval> roots = index->done;
  for (const auto& [tile, root] : tiles->roots) roots[tile] = root;
  auto top_bytes = write_top_levels(config, build->layout, roots, db);
  if (!top_bytes) return top_bytes.error();
  const PhaseTimes times{index->seconds, tiles->wall_seconds, seconds_since(top_start)};

  // 6. Finish: stats, meta marked complete, one sync.
  BuildSummary summary = summarize(*build, *index, *tiles, *top_bytes, times, total_start);
  summary.stats["embree"] = {{"version", device->version()}, {"native_ray_packet", device->native_ray_packet()}};
  if (Status s = finish(db, meta, summary, total_start); !s) return s.error();
  if (config.report_tile_costs) {  // in the printed summary only, never in the meta
    nlohmann::json costs = nlohmann::json::array();
    for (const TileCost& c : tiles->costs)
      costs.push_back({{"morton", TileLayout::morton_index(c.tile)}, {"cpu_seconds", c.cpu_seconds},
                       {"wall_seconds", c.wall_seconds}, {"hit_texels", c.hit_texels}, {"blob_bytes", c.blob_bytes},
                       {"triangles", c.triangles},
                       {"seconds", {{"bvh", c.bvh_seconds}, {"rays", c.ray_seconds}, {"entry_rule", c.entry_seconds},
                                    {"caps", c.cap_seconds}, {"encode", c.encode_seconds}}}});
    summary.stats["tile_costs"] = std::move(costs);
  }
  return summary;
}

}  // namespace shadowtiles
