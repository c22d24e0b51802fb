// The build's render + encode phase (docs/architecture.md §9): worker threads take the tiles still
// to do, one at a time each, cast the tile's dual depth map (builder/dual_depth_renderer.hpp),
// encode every requested method (builder/tile_encoder.hpp), and commit the tile's blobs, info
// records, previews and progress record in one LMDB transaction, so a killed build resumes at tile
// granularity with nothing half-written.
// Errors: the first error of any worker stops them all and is returned; tiles committed before it
// stay committed (a resume skips them).
// Thread safety: run_tile_pipeline runs its own threads; the store must allow concurrent writers
// (store::Store serialises write transactions).
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "builder/dual_depth_renderer.hpp"
#include "builder/tile_encoder.hpp"
#include "codec/tile_layout.hpp"
#include "common/result.hpp"
#include "store/lmdb_store.hpp"
#include "store/method.hpp"

namespace shadowtiles {

// What the workers did, summed over threads (per-thread sums of seconds, not wall time).
struct TilePipelineTotals {
  DualDepthStats depth;
  double encode_seconds = 0;
  double store_seconds = 0;
  uint64_t stored_tiles = 0;
  uint64_t blob_bytes = 0;
  uint64_t preview_bytes = 0;
  double preview_seconds = 0;
  std::map<std::string, uint64_t> bytes_by_method;
  std::map<std::string, uint64_t> raw_bytes_by_method;
  std::map<std::string, uint64_t> reference_bytes_by_method;
  std::map<std::string, double> encode_seconds_by_method;
  void add(const TilePipelineTotals& other);
};

struct TilePipelineInput {
  const std::vector<store::Method>* methods = nullptr;
  const TileLayout* layout = nullptr;
  const DualDepthRenderer* renderer = nullptr;
  TileEncodeOptions encode_options;
  int zstd_level = 0;
  unsigned threads = 1;
  // Test hook: SIGKILL the process once this many tiles are committed (0: never).
  uint64_t debug_kill_after_tiles = 0;
  // Called about once a second with a progress line (may be empty).
  std::function<void(const std::string&)> on_progress;
};

// One tile's measured cost, for fitting the shard plan's work model (`build --tile-costs`).
struct TileCost {
  TileCoord tile;
  double cpu_seconds = 0;   // the worker thread's CPU time on the tile: render, encode, previews, commit
  double wall_seconds = 0;  // the same span in wall time (includes waiting for the store's write lock)
  uint64_t hit_texels = 0;
  uint64_t blob_bytes = 0;  // all methods
  // Where the tile's time went (thread seconds, as the build JSON's *_thread_sum; encode includes the
  // blobs and previews, and the store write is in cpu and wall only): a tile of misses still pays its
  // rays and per-texel passes, and a city tile its cap pass.
  double bvh_seconds = 0, ray_seconds = 0, entry_seconds = 0, cap_seconds = 0, encode_seconds = 0;
  uint64_t triangles = 0;  // in the tile's BVH
};

struct TilePipelineResult {
  TilePipelineTotals totals;
  std::vector<TileCost> costs;  // one per tile committed in this run, in commit order
  std::map<TileCoord, DepthInterval> roots;  // each committed tile's root interval (a miss if empty)
  unsigned threads = 0;                      // worker threads actually started
  double wall_seconds = 0;
};

Result<TilePipelineResult> run_tile_pipeline(const TilePipelineInput& input, const std::vector<TileCoord>& todo,
                                             store::Store& db);

}  // namespace shadowtiles
