#include "builder/tile_pipeline.hpp"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <mutex>
#include <optional>
#include <thread>

#include <time.h>

#include "builder/tile_preview_builder.hpp"
#include "store/blob.hpp"
#include "store/store_layout.hpp"
#include "store/tile_info.hpp"
#include "store/tile_key.hpp"
#include "store/tile_preview.hpp"

namespace shadowtiles {
namespace {

using Clock = std::chrono::steady_clock;

// The store commits without a sync (one forced sync ends the build, builder/build_job.cpp). This
// many bytes of committed blobs, flushed from the pipeline's otherwise idle thread while the workers
// run, leave that last sync little to write.
constexpr uint64_t kSyncEveryBytes = uint64_t(256) << 20;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// CPU time of the calling thread: a tile's cost that the machine's load does not inflate.
double thread_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) + double(t.tv_nsec) * 1e-9;
}

// What one tile cost and gave, beside the totals it adds to: its row of `build --tile-costs`.
struct TileOutcome {
  DualDepthStats depth;
  uint64_t blob_bytes = 0;
  double encode_seconds = 0;
  DepthInterval root;  // a miss when nothing covers the tile
};

// One tile: render, encode every method, and gather the puts of its one transaction.
Status process_tile(const TilePipelineInput& input, TileCoord tile, TilePipelineTotals& mine,
                    std::atomic<uint64_t>& rays_done, std::vector<store::Store::Put>& puts, TileOutcome& outcome,
                    RenderBuffers& buffers) {
  DualDepthStats& depth = outcome.depth;
  DepthInterval& root = outcome.root;
  auto intervals = input.renderer->render(tile, &depth, &buffers);
  if (!intervals) return intervals.error();
  mine.depth.add(depth);
  rays_done += depth.rays;

  auto encode_start = Clock::now();
  const bool empty = intervals->all_missed();
  root = DepthInterval{};  // an empty tile's root is a miss: lit
  if (!empty) {
    auto encoding = encode_tile(*input.methods, *intervals, input.encode_options);
    if (!encoding) return encoding.error();
    if (encoding->has_root) root = encoding->root;
    // A payload byte-identical to an earlier method's of this tile (MMH where its merge finds
    // nothing) reuses that method's zstd frame, and its preview where both decode alike.
    struct Stored {
      store::Method method;
      const std::vector<uint8_t>* payload;
      size_t blob_put;  // index in `puts`
      store::TilePreview preview;
    };
    std::vector<Stored> stored;
    for (EncodedPayload& encoded : encoding->payloads) {
      auto blob_start = Clock::now();
      const Stored* same = nullptr;
      for (const Stored& earlier : stored)
        if (*earlier.payload == encoded.payload) same = &earlier;
      std::vector<uint8_t> blob;
      if (same) {
        auto copy = store::copy_blob_as(encoded.method, puts[same->blob_put].value);
        if (!copy) return copy.error();
        blob = std::move(*copy);
      } else {
        blob = store::encode_blob(encoded.method, encoded.payload, 0, input.zstd_level);
      }
      const char* name = store::method_name(encoded.method);
      mine.encode_seconds_by_method[name] += encoded.seconds + seconds_since(blob_start);
      outcome.blob_bytes += blob.size();
      mine.bytes_by_method[name] += blob.size();
      mine.raw_bytes_by_method[name] += encoded.payload.size();
      mine.reference_bytes_by_method[name] += encoded.reference_bytes;
      auto key = store::encode_tile_key({encoded.method, input.layout->tile_level(), tile.x, tile.y});
      // The tile's info record goes with its blob (same transaction, same key).
      store::TileInfo info{encoding->has_root, root.lower, root.upper, blob.size(), encoded.payload.size()};
      auto info_bytes = store::encode_tile_info(info);
      puts.push_back({store::Database::tileinfo, {key.begin(), key.end()}, {info_bytes.begin(), info_bytes.end()}});
      const size_t blob_put = puts.size();
      puts.push_back({store::Database::tiles, {key.begin(), key.end()}, std::move(blob)});
      // The inspector's preview of this tile, committed with it (store/tile_preview.hpp).
      auto preview_start = Clock::now();
      Result<store::TilePreview> preview =
          same && previews_decode_alike(same->method, encoded.method)
              ? Result<store::TilePreview>(same->preview)
              : make_tile_preview(*intervals, encoded.method, encoded.payload);
      if (!preview) return preview.error();
      auto preview_blob = store::encode_preview(encoded.method, *preview, input.zstd_level);
      mine.preview_seconds += seconds_since(preview_start);
      mine.preview_bytes += preview_blob.size();
      puts.push_back({store::Database::preview, {key.begin(), key.end()}, std::move(preview_blob)});
      stored.push_back({encoded.method, &encoded.payload, blob_put, std::move(*preview)});
    }
    ++mine.stored_tiles;
  }
  const auto key = store::progress_key(tile.x, tile.y);
  const auto record = store::encode_progress({!empty, root.lower, root.upper});
  puts.push_back({store::Database::progress, {key.begin(), key.end()}, {record.begin(), record.end()}});
  outcome.encode_seconds = seconds_since(encode_start);
  mine.encode_seconds += outcome.encode_seconds;
  mine.blob_bytes += outcome.blob_bytes;
  buffers.intervals = std::move(*intervals);  // the next tile renders into the same pages
  return {};
}

}  // namespace

void TilePipelineTotals::add(const TilePipelineTotals& other) {
  depth.add(other.depth);
  encode_seconds += other.encode_seconds;
  store_seconds += other.store_seconds;
  stored_tiles += other.stored_tiles;
  blob_bytes += other.blob_bytes;
  preview_bytes += other.preview_bytes;
  preview_seconds += other.preview_seconds;
  for (auto& [k, v] : other.bytes_by_method) bytes_by_method[k] += v;
  for (auto& [k, v] : other.raw_bytes_by_method) raw_bytes_by_method[k] += v;
  for (auto& [k, v] : other.reference_bytes_by_method) reference_bytes_by_method[k] += v;
  for (auto& [k, v] : other.encode_seconds_by_method) encode_seconds_by_method[k] += v;
}

Result<TilePipelineResult> run_tile_pipeline(const TilePipelineInput& input, const std::vector<TileCoord>& todo,
                                             store::Store& db) {
  auto start = Clock::now();
  std::atomic<size_t> next{0};
  std::atomic<uint64_t> committed{0};
  std::atomic<uint64_t> committed_bytes{0};
  std::atomic<uint64_t> rays_done{0};
  std::atomic<bool> failed{false};
  std::mutex result_mutex;
  TilePipelineResult result;  // totals and roots guarded by result_mutex
  std::optional<Error> first_error;
  auto fail = [&](Error error) {
    std::lock_guard lock(result_mutex);
    if (!first_error) first_error = std::move(error);
    failed = true;
  };
  // The progress loop waits on this rather than polling, so the build's wall time does not wait for
  // the next poll after the last tile (up to 50 ms, a few percent of a small scene's ray casting).
  std::condition_variable workers_finished;
  unsigned workers_done = 0;  // guarded by result_mutex
  auto worker = [&] {
    TilePipelineTotals mine;
    RenderBuffers buffers;  // this worker's tile buffers, reused tile after tile
    while (!failed) {
      const size_t i = next++;
      if (i >= todo.size()) break;
      const TileCoord tile = todo[i];
      const double cpu_start = thread_cpu_seconds();
      const auto wall_start = Clock::now();
      std::vector<store::Store::Put> puts;
      TileOutcome outcome;
      if (Status s = process_tile(input, tile, mine, rays_done, puts, outcome, buffers); !s) {
        fail(s.error());
        break;
      }
      auto store_start = Clock::now();
      if (Status s = db.write(puts); !s) {
        fail(s.error());
        break;
      }
      mine.store_seconds += seconds_since(store_start);
      committed_bytes += outcome.blob_bytes;
      const DualDepthStats& depth = outcome.depth;
      TileCost cost{tile, thread_cpu_seconds() - cpu_start, seconds_since(wall_start), depth.hits,
                    outcome.blob_bytes};
      cost.bvh_seconds = depth.bvh_seconds;
      cost.ray_seconds = depth.ray_seconds;
      cost.entry_seconds = depth.entry_seconds;
      cost.cap_seconds = depth.cap_seconds;
      cost.encode_seconds = outcome.encode_seconds;
      cost.triangles = depth.triangles;
      {
        std::lock_guard lock(result_mutex);
        result.roots[tile] = outcome.root;
        result.costs.push_back(cost);
      }
      const uint64_t count = ++committed;
      if (input.debug_kill_after_tiles && count >= input.debug_kill_after_tiles) std::raise(SIGKILL);
    }
    std::lock_guard lock(result_mutex);
    result.totals.add(mine);
    ++workers_done;
    workers_finished.notify_one();
  };
  std::vector<std::thread> threads;
  result.threads = std::min<unsigned>(input.threads, std::max<size_t>(todo.size(), 1));
  for (unsigned t = 0; t < result.threads; ++t) threads.emplace_back(worker);

  // Progress line about once a second while the workers run, and the committed tiles flushed.
  auto last_report = Clock::now();
  uint64_t synced_bytes = 0;
  for (;;) {
    {
      std::unique_lock lock(result_mutex);
      if (workers_finished.wait_for(lock, std::chrono::milliseconds(50),
                                    [&] { return workers_done == result.threads; }))
        break;
    }
    if (const uint64_t bytes = committed_bytes; bytes - synced_bytes >= kSyncEveryBytes && !failed) {
      synced_bytes = bytes;
      if (Status s = db.sync(); !s) fail(s.error());
    }
    if (input.on_progress && seconds_since(last_report) >= 1.0) {
      last_report = Clock::now();
      const double elapsed = seconds_since(start);
      const uint64_t n = committed;
      const double rate = elapsed > 0 ? double(rays_done) / elapsed : 0;
      const double eta = n ? elapsed / double(n) * double(todo.size() - n) : 0;
      char line[160];
      std::snprintf(line, sizeof line, "tiles %llu/%zu  %.2f Mrays/s  ETA %.0f s",
                    static_cast<unsigned long long>(n), todo.size(), rate / 1e6, eta);
      input.on_progress(line);
    }
  }
  for (auto& t : threads) t.join();
  if (first_error) return *first_error;
  result.wall_seconds = seconds_since(start);
  return result;
}

}  // namespace shadowtiles
