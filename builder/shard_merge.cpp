#include "builder/shard_merge.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <queue>

#include <spdlog/spdlog.h>

#include "builder/depth_interval.hpp"
#include "builder/top_levels.hpp"
#include "codec/store_meta.hpp"
#include "codec/tile_layout.hpp"
#include "store/blob.hpp"
#include "store/lmdb_store.hpp"
#include "store/map_advice.hpp"
#include "store/serving_lock.hpp"
#include "store/store_layout.hpp"
#include "store/tile_info.hpp"
#include "store/tile_key.hpp"

namespace shadowtiles {
namespace {

using Clock = std::chrono::steady_clock;
using Bytes = std::vector<uint8_t>;
double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }
Bytes bytes_of(std::string_view text) { return {text.begin(), text.end()}; }
constexpr const char* kMergeMarkerKey = store::kMetaMergeKey;  // a merge in progress (removed when done)

Error invalid(const std::string& message) { return make_error(ErrorCode::invalid_input, message); }

struct Shard {
  std::filesystem::path path;
  std::unique_ptr<store::Store> store;
  StoreMeta meta;
  std::string name() const {
    return path.string() + " (shard " + std::to_string(meta.shard->index) + "/" + std::to_string(meta.shard->count) + ")";
  }
};

Result<std::unique_ptr<store::Store>> open_read_only(const std::filesystem::path& path) {
  store::Store::Options options;
  options.mode = store::Store::Mode::read_only;
  options.no_readahead = true;  // streamed once, in key order
  return store::Store::open(path, options);
}

Result<StoreMeta> read_meta(const store::Store& db, const std::filesystem::path& path) {
  auto text = db.get(store::Database::meta, store::as_bytes(kMetaBuildKey));
  if (!text) return text.error();
  if (!text->has_value()) return invalid(path.string() + ": no build meta (not a shadowtiles store)");
  return StoreMeta::parse(std::string_view(reinterpret_cast<const char*>((*text)->data()), (*text)->size()));
}

// Morton index of a tile key's tile (tiles, tileinfo) or of a progress key (x u32 | y u32, BE).
std::optional<uint64_t> morton_of_key(store::Database db, std::span<const uint8_t> key, const StoreMeta& meta,
                                      unsigned tile_level) {
  TileCoord tile;
  if (db == store::Database::progress) {
    auto decoded = store::decode_progress_key(key);
    if (!decoded) return std::nullopt;
    tile = {decoded->x, decoded->y};
  } else {
    auto decoded = store::decode_tile_key(key);
    if (!decoded || decoded->level != tile_level || !meta.has_method(decoded->method)) return std::nullopt;
    tile = {decoded->x, decoded->y};
  }
  uint32_t side = meta.resolution / meta.tile_size;
  if (tile.x >= side || tile.y >= side) return std::nullopt;
  return TileLayout::morton_index(tile);
}

// All the checks that need no tile data: one build, every share once, shares tiling the map.
Status check_shards(std::vector<Shard>& shards) {
  const Shard& first = shards.front();
  for (const Shard& s : shards) {
    if (s.meta.config_hash != first.meta.config_hash)
      return invalid("shard store " + s.name() + " belongs to build " + s.meta.config_hash + ", but " + first.name() +
                     " to build " + first.meta.config_hash + ": shards of different builds cannot be merged");
    if (s.meta.shard->count != first.meta.shard->count)
      return invalid("shard store " + s.name() + " is one of " + std::to_string(s.meta.shard->count) + " shards, " +
                     first.name() + " one of " + std::to_string(first.meta.shard->count));
  }
  std::sort(shards.begin(), shards.end(), [](const Shard& a, const Shard& b) { return a.meta.shard->index < b.meta.shard->index; });
  uint32_t count = first.meta.shard->count;
  for (size_t i = 1; i < shards.size(); ++i)
    if (shards[i].meta.shard->index == shards[i - 1].meta.shard->index)
      return invalid("shard stores " + shards[i - 1].path.string() + " and " + shards[i].path.string() + " are both shard " +
                     std::to_string(shards[i].meta.shard->index) + "/" + std::to_string(count) + " (overlapping tiles)");
  std::vector<bool> present(count, false);
  for (const Shard& s : shards) present[s.meta.shard->index] = true;
  for (uint32_t i = 0; i < count; ++i)
    if (!present[i])
      return invalid("shard " + std::to_string(i) + "/" + std::to_string(count) +
                     " is missing: its tiles would be absent (give all " + std::to_string(count) + " shard stores)");
  uint64_t tile_count = uint64_t(first.meta.resolution / first.meta.tile_size) * (first.meta.resolution / first.meta.tile_size);
  uint64_t expected_begin = 0;
  for (const Shard& s : shards) {
    if (s.meta.shard->morton_begin != expected_begin)
      return invalid("shard store " + s.name() + " starts at Morton tile " + std::to_string(s.meta.shard->morton_begin) +
                     " but the previous share ends at " + std::to_string(expected_begin) +
                     (s.meta.shard->morton_begin < expected_begin ? " (overlapping tiles)" : " (missing tiles)"));
    expected_begin = s.meta.shard->morton_end;
  }
  if (expected_begin != tile_count)
    return invalid("shard store " + shards.back().name() + " ends at Morton tile " + std::to_string(expected_begin) +
                   " of " + std::to_string(tile_count) + " (missing tiles)");
  return {};
}

// A shard's progress records must be exactly its share's tiles with triangles; tile info must
// accompany every blob.
Status check_shard_contents(const Shard& s, unsigned tile_level) {
  uint64_t inside = 0;
  std::optional<std::string> outside;
  Status walked = s.store->for_each(store::Database::progress, {}, [&](std::span<const uint8_t> key, std::span<const uint8_t>) {
    auto m = morton_of_key(store::Database::progress, key, s.meta, tile_level);
    if (!m || *m < s.meta.shard->morton_begin || *m >= s.meta.shard->morton_end) {
      outside = m ? "Morton tile " + std::to_string(*m) : std::string("a malformed progress key");
      return false;
    }
    ++inside;
    return true;
  });
  if (!walked) return walked.error();
  if (outside)
    return invalid("shard store " + s.name() + " holds " + *outside + " outside its share [" +
                   std::to_string(s.meta.shard->morton_begin) + ", " + std::to_string(s.meta.shard->morton_end) +
                   ") (overlapping tiles)");
  if (inside != s.meta.shard->tiles)
    return invalid("shard store " + s.name() + " committed " + std::to_string(inside) + " of its " +
                   std::to_string(s.meta.shard->tiles) + " tiles (missing tiles): rerun its build to resume it");
  auto tiles = s.store->entry_count(store::Database::tiles);
  auto infos = s.store->entry_count(store::Database::tileinfo);
  if (!tiles) return tiles.error();
  if (!infos) return infos.error();
  if (*tiles != *infos)
    return invalid("shard store " + s.name() + " has " + std::to_string(*tiles) + " tile blobs but " +
                   std::to_string(*infos) + " tile info records (built by a builder without tile info?): rebuild it");
  return {};
}

// One shard's position in one database: a chunk of entries read ahead, refilled after the last key.
struct ShardCursor {
  Shard* shard;
  std::deque<std::pair<Bytes, Bytes>> chunk;
  Bytes last_read;  // empty: nothing read yet
  bool exhausted = false;
};

// Copies the next chunk_bytes of entries (short read transactions: the shard's map is only touched
// inside them), drops each copied value's pages from this process right away (resident memory stays
// bounded by the chunks, whatever the shard's size), then asks the kernel to fetch the chunk after
// it, so reading the shard (values scattered in its file) overlaps the copying of this one.
Status refill(ShardCursor& cursor, store::Database db, const MergeConfig& config) {
  const bool large_values = db == store::Database::tiles || db == store::Database::preview;
  uint64_t bytes = 0;
  size_t before = cursor.chunk.size();
  Status s = cursor.shard->store->for_each_after(db, cursor.last_read, [&](std::span<const uint8_t> key, std::span<const uint8_t> value) {
    cursor.chunk.emplace_back(Bytes(key.begin(), key.end()), Bytes(value.begin(), value.end()));
    if (large_values) store::advise_done_with(value);
    bytes += key.size() + value.size();
    return bytes < config.chunk_bytes;
  });
  if (!s) return s.error();
  if (cursor.chunk.size() == before) {
    cursor.exhausted = true;
    return {};
  }
  cursor.last_read = cursor.chunk.back().first;
  if (!large_values) return {};
  uint64_t ahead = 0;
  return cursor.shard->store->for_each_after(db, cursor.last_read, [&](std::span<const uint8_t> key, std::span<const uint8_t> value) {
    store::advise_will_need(value);
    ahead += key.size() + value.size();
    return ahead < config.chunk_bytes;
  });
}

struct DatabaseTotals {
  uint64_t entries = 0;
  uint64_t bytes = 0;
};

double peak_memory_mib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_maxrss) / 1024.0;
}

}  // namespace

Result<MergeSummary> run_merge(const MergeConfig& config) {
  auto start = Clock::now();
  if (config.shards.empty()) return invalid("no shard stores given");
  if (config.out.empty()) return invalid("no output store given (--out)");
  std::vector<Shard> shards;
  for (const auto& path : config.shards) {
    std::error_code ec;
    if (std::filesystem::exists(path, ec) && std::filesystem::exists(config.out, ec) &&
        std::filesystem::equivalent(path, config.out, ec))
      return invalid("--out " + config.out.string() + " is one of the shard stores");
    auto opened = open_read_only(path);
    if (!opened) return make_error(opened.error().code, "shard store " + path.string() + ": " + opened.error().message);
    auto meta = read_meta(**opened, path);
    if (!meta) return make_error(meta.error().code, "shard store " + path.string() + ": " + meta.error().message);
    if (!meta->shard) return invalid(path.string() + " is not a shard store (built without --shard)");
    Shard shard{path, std::move(*opened), std::move(*meta)};
    if (!shard.meta.shard->complete)
      return invalid("shard store " + shard.name() + " is not finished: rerun its build (it resumes)");
    shards.push_back(std::move(shard));
  }
  if (Status s = check_shards(shards); !s) return s.error();
  auto layout = shards.front().meta.layout();
  if (!layout) return layout.error();
  const unsigned tile_level = layout->tile_level();
  for (const Shard& s : shards)
    if (Status st = check_shard_contents(s, tile_level); !st) return st.error();
  const std::string build_id = shards.front().meta.config_hash;

  // The output: a new store, or the same merge resumed.
  store::Store::Options out_options;
  out_options.mode = store::Store::Mode::read_write;
  // Room for every shard's file from the start: growing the map aborts and redoes a transaction.
  uint64_t shard_file_bytes = 0;
  for (const Shard& s : shards) {
    std::error_code ec;
    const uintmax_t bytes = std::filesystem::file_size(s.path / "data.mdb", ec);
    if (!ec) shard_file_bytes += bytes;
  }
  out_options.initial_map_size = std::max(config.initial_map_size, shard_file_bytes + shard_file_bytes / 8);
  out_options.no_sync = true;
  auto opened = store::Store::open(config.out, out_options);
  if (!opened) return opened.error();
  auto serving_lock = store::ServingLock::acquire(config.out, store::ServingLock::Kind::build);
  if (!serving_lock) return serving_lock.error();
  store::Store& out = **opened;
  nlohmann::json marker = {{"config_hash", build_id}, {"shards", shards.front().meta.shard->count}};
  auto existing = out.get(store::Database::meta, store::as_bytes(kMetaBuildKey));
  auto existing_marker = out.get(store::Database::meta, store::as_bytes(kMergeMarkerKey));
  if (!existing) return existing.error();
  if (!existing_marker) return existing_marker.error();
  bool resuming = false;
  if (existing->has_value()) {
    auto old = StoreMeta::parse(std::string_view(reinterpret_cast<const char*>((*existing)->data()), (*existing)->size()));
    bool same_merge = old && old->config_hash == build_id && !old->shard && existing_marker->has_value() &&
                      nlohmann::json::parse(std::string((*existing_marker)->begin(), (*existing_marker)->end()), nullptr,
                                            false) == marker;
    bool done = old && old->config_hash == build_id && !old->shard && old->complete && !existing_marker->has_value();
    if (done) {
      spdlog::info("{} already holds this build, complete: nothing to merge", config.out.string());
      MergeSummary summary;
      summary.stats = {{"already_complete", true}, {"build_id", build_id}};
      return summary;
    }
    if (same_merge) {
      resuming = true;
    } else if (!config.overwrite) {
      return invalid("store " + config.out.string() + " holds another build; pass --overwrite or choose another --out");
    } else {
      for (auto which : {store::Database::meta, store::Database::tiles, store::Database::top, store::Database::progress,
                         store::Database::tileinfo, store::Database::preview})
        if (Status s = out.clear(which); !s) return s.error();
    }
  } else {
    // Empty store expected: anything in it would break the append order.
    for (auto which : {store::Database::tiles, store::Database::tileinfo, store::Database::preview, store::Database::progress}) {
      auto n = out.entry_count(which);
      if (!n) return n.error();
      if (*n && !config.overwrite) return invalid("store " + config.out.string() + " is not empty; pass --overwrite or choose another --out");
    }
  }
  StoreMeta meta = shards.front().meta;
  meta.shard.reset();
  meta.complete = false;
  meta.build_stats = nlohmann::json::object();
  {
    std::string text = meta.to_json().dump(), marker_text = marker.dump();
    std::vector<store::Store::Put> puts{{store::Database::meta, bytes_of(kMetaBuildKey), bytes_of(text)},
                                        {store::Database::meta, bytes_of(kMergeMarkerKey), bytes_of(marker_text)}};
    if (Status s = out.write(puts); !s) return s.error();
  }
  if (resuming) spdlog::info("resuming the merge into {}", config.out.string());

  // Stream each database: k-way merge of the shards' chunks, appended in bounded transactions.
  uint64_t transactions = 0;
  std::map<std::string, DatabaseTotals> totals;
  uint64_t blob_bytes_copied = 0;
  auto copy_start = Clock::now();
  auto last_report = Clock::now();
  for (store::Database db : {store::Database::tiles, store::Database::tileinfo, store::Database::preview,
                             store::Database::progress}) {
    auto resume_after = out.last_key(db);
    if (!resume_after) return resume_after.error();
    std::vector<ShardCursor> cursors;
    for (Shard& s : shards) cursors.push_back({&s, {}, resume_after->value_or(Bytes{}), false});
    // Min-heap of (key, cursor index); the key is the cursor's front.
    auto greater = [&](size_t a, size_t b) { return cursors[a].chunk.front().first > cursors[b].chunk.front().first; };
    std::priority_queue<size_t, std::vector<size_t>, decltype(greater)> heap(greater);
    for (size_t i = 0; i < cursors.size(); ++i) {
      if (Status s = refill(cursors[i], db, config); !s) return s.error();
      if (!cursors[i].chunk.empty()) heap.push(i);
    }
    std::vector<store::Store::Put> batch;
    uint64_t batch_bytes = 0;
    Bytes previous_key = resume_after->value_or(Bytes{});
    size_t previous_shard = SIZE_MAX;
    auto flush = [&]() -> Status {
      if (batch.empty()) return {};
      if (Status s = out.append(batch); !s) return s;
      batch.clear();
      batch_bytes = 0;
      ++transactions;
      if (config.debug_kill_after_transactions && transactions >= config.debug_kill_after_transactions) std::raise(SIGKILL);
      if (config.on_progress && seconds_since(last_report) >= 1.0) {
        last_report = Clock::now();
        double elapsed = seconds_since(copy_start);
        char line[160];
        std::snprintf(line, sizeof line, "%s: %llu entries, %.1f MB of blobs, %.0f MB/s", store::database_name(db),
                      (unsigned long long)totals[store::database_name(db)].entries, blob_bytes_copied / 1e6,
                      elapsed > 0 ? blob_bytes_copied / 1e6 / elapsed : 0.0);
        config.on_progress(line);
      }
      return {};
    };
    while (!heap.empty()) {
      size_t i = heap.top();
      heap.pop();
      ShardCursor& cursor = cursors[i];
      auto [key, value] = std::move(cursor.chunk.front());
      cursor.chunk.pop_front();
      const Shard& shard = *cursor.shard;
      if (!previous_key.empty() && key == previous_key)
        return invalid("shard stores " + shards[previous_shard == SIZE_MAX ? i : previous_shard].name() + " and " +
                       shard.name() + " both hold " + store::database_name(db) + " key of Morton tile " +
                       std::to_string(morton_of_key(db, key, shard.meta, tile_level).value_or(0)) + " (overlapping tiles)");
      auto m = morton_of_key(db, key, shard.meta, tile_level);
      if (!m || *m < shard.meta.shard->morton_begin || *m >= shard.meta.shard->morton_end)
        return invalid("shard store " + shard.name() + " holds a " + store::database_name(db) + " entry " +
                       (m ? "of Morton tile " + std::to_string(*m) + " outside its share" : std::string("with a malformed key")) +
                       " (overlapping tiles)");
      if (db == store::Database::tiles) {
        // Never carry a damaged blob into the final store.
        if (auto header = store::check_blob(value); !header)
          return make_error(ErrorCode::corrupt_data, "shard store " + shard.name() + ": " + header.error().message);
        blob_bytes_copied += value.size();
      } else if (db == store::Database::tileinfo) {
        if (auto info = store::decode_tile_info(value); !info)
          return make_error(info.error().code, "shard store " + shard.name() + ": " + info.error().message);
      }
      auto& t = totals[store::database_name(db)];
      ++t.entries;
      t.bytes += key.size() + value.size();
      batch_bytes += key.size() + value.size();
      previous_key = key;
      previous_shard = i;
      batch.push_back({db, std::move(key), std::move(value)});
      if (batch_bytes >= config.transaction_bytes)
        if (Status s = flush(); !s) return s.error();
      if (cursor.chunk.empty())
        if (Status s = refill(cursor, db, config); !s) return s.error();
      if (!cursor.chunk.empty()) heap.push(i);
    }
    if (Status s = flush(); !s) return s.error();
  }
  double copy_seconds = seconds_since(copy_start);
  for (Shard& s : shards) s.store.reset();  // done with the shards

  // Top levels from the merged info records: one root per stored tile position.
  auto top_start = Clock::now();
  const uint32_t side = layout->tiles_per_side();
  std::vector<DepthInterval> roots(size_t(side) * side);
  nlohmann::json bytes_by_method = nlohmann::json::object(), payload_by_method = nlohmann::json::object();
  std::vector<bool> stored(size_t(side) * side, false);
  std::optional<Error> bad;
  Status walked = out.for_each(store::Database::tileinfo, {}, [&](std::span<const uint8_t> key, std::span<const uint8_t> value) {
    auto tile = store::decode_tile_key(key);
    auto info = store::decode_tile_info(value);
    if (!tile || !info) { bad = tile ? info.error() : tile.error(); return false; }
    size_t at = size_t(tile->y) * side + tile->x;
    stored[at] = true;
    if (info->has_root) roots[at] = DepthInterval{info->root_lower, info->root_upper};
    const char* name = store::method_name(tile->method);
    bytes_by_method[name] = bytes_by_method.value(name, uint64_t{0}) + info->blob_bytes;
    payload_by_method[name] = payload_by_method.value(name, uint64_t{0}) + info->payload_bytes;
    return true;
  });
  if (!walked) return walked.error();
  if (bad) return *bad;
  auto tops = encode_top_levels(meta.methods, side, std::move(roots), tile_level, shards.front().meta.shard->zstd_level);
  if (!tops) return tops.error();
  nlohmann::json top_bytes = nlohmann::json::object();
  std::vector<store::Store::Put> puts;
  for (TopLevelBlob& top : *tops) {
    top_bytes[store::method_name(top.method)] = top.blob.size();
    puts.push_back({store::Database::top, bytes_of(top_tree_key(top.method)), std::move(top.blob)});
  }
  double top_seconds = seconds_since(top_start);

  uint64_t with_triangles = 0;
  for (const Shard& s : shards) with_triangles += s.meta.shard->tiles;
  uint64_t stored_tiles = std::count(stored.begin(), stored.end(), true);
  nlohmann::json shard_paths = nlohmann::json::array();
  for (const Shard& s : shards) shard_paths.push_back(s.path.string());
  nlohmann::json databases = nlohmann::json::object();
  for (auto& [name, t] : totals) databases[name] = {{"entries", t.entries}, {"bytes", t.bytes}};
  // What each share's rays ran on (shards may run on different hosts): as each shard recorded it.
  nlohmann::json embree_by_shard = nlohmann::json::array();
  for (const Shard& s : shards) embree_by_shard.push_back(s.meta.build_stats.value("embree", nlohmann::json()));
  meta.build_stats = {
      {"tiles", {{"total", layout->tile_count()}, {"with_triangles", with_triangles}, {"stored", stored_tiles}}},
      {"rays", with_triangles * uint64_t(meta.tile_size) * meta.tile_size},
      {"bytes_by_method", bytes_by_method},
      {"payload_bytes_by_method", payload_by_method},
      {"top_bytes_by_method", top_bytes},
      {"merge", {{"shards", shard_paths}, {"resumed", resuming}, {"transactions", transactions},
                 {"copied", databases}, {"blob_bytes_copied", blob_bytes_copied},
                 {"blob_mb_per_second", copy_seconds > 0 ? blob_bytes_copied / 1e6 / copy_seconds : 0.0}}},
      {"seconds", {{"merge_copy", copy_seconds}, {"top_levels", top_seconds}}},
      {"embree_by_shard", embree_by_shard},
      {"peak_memory_mib", peak_memory_mib()},
  };
  meta.complete = true;
  std::string text = meta.to_json().dump();
  puts.push_back({store::Database::meta, bytes_of(kMetaBuildKey), bytes_of(text)});
  std::vector<store::Store::Delete> deletes{{store::Database::meta, bytes_of(kMergeMarkerKey)}};
  if (Status s = out.write(puts, deletes); !s) return s.error();
  if (Status s = out.sync(); !s) return s.error();
  MergeSummary summary;
  summary.stats = meta.build_stats;
  summary.stats["seconds"]["total"] = seconds_since(start);
  summary.stats["build_id"] = build_id;
  return summary;
}

}  // namespace shadowtiles
