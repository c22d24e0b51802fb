// Store: one LMDB environment (a directory) holding one build (docs/architecture.md §9). Keys and values are
// plain bytes; tile keys come from tile_key.hpp and values are usually blobs (blob.hpp), but this
// layer knows neither trees nor blob contents.
//
// Named databases (FORMAT: the names are stored in the environment):
//   meta      build metadata (JSON under string keys)
//   tiles     tile blobs under TileKey bytes
//   top       top-level tree and skip list
//   progress  builder bookkeeping for resuming an interrupted build (may be absent in read-only)
//   preview   per-tile previews under TileKey bytes (store/tile_preview.hpp; absent in older stores)
//   tileinfo  per stored tile: root interval and sizes (tile_info.hpp), same key as `tiles`
//
// Modes. read_only (serving): MDB_RDONLY | MDB_NOTLS, so any thread of a pool may read and reader
// slots do not leak per thread; stale reader slots of dead processes are cleared at open
// (mdb_reader_check). read_write (building): creates the directory and databases, MDB_NOTLS, and
// MDB_NOSYNC when Options::no_sync (then call sync() when done; the destructor also syncs).
//
// Map growth. A write that hits MDB_MAP_FULL is aborted, the map doubled (up to
// Options::max_map_size) and the write retried, so callers never see a half-written transaction.
// Replacing the map needs every transaction of this process closed: growth waits up to
// Options::resize_wait for open Snapshots, get/for_each calls and compact_copy to finish, and fails
// (io_error, nothing written) if they do not. So do not hold a Snapshot across write() on the same
// thread, and keep Snapshots short. When another process grew the map, readers here see
// MDB_MAP_RESIZED; the store adopts the new size and retries transparently.
//
// Errors: open of a directory without a store → not_found; a damaged file → corrupt_data;
// a newer LMDB format → unsupported; full map at the cap or a full disk → out_of_space; writing to a
// read-only store, empty or over-long keys → invalid_input; other LMDB/OS failures → io_error.
// Messages name the directory and the LMDB error.
//
// Thread safety: every Store member may be called concurrently from any thread. Writes are
// serialised internally (LMDB allows one writer). A Snapshot is used by one thread at a time but may
// move between threads. Never open the same directory twice in one process (LMDB's rule: its file
// locks are per process); share one Store instead. Never place a store on NFS.
//
// Untrusted input: keys and values are opaque bytes, any content is safe. The files themselves are
// trusted: LMDB does not validate pages against malicious modification.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "common/result.hpp"
#include "store/txn_gate.hpp"

// LMDB's handle types, declared here so includers do not need lmdb.h.
struct MDB_env;
struct MDB_txn;

namespace shadowtiles::store {

enum class Database { meta, tiles, top, progress, preview, tileinfo };
inline constexpr size_t kDatabaseCount = 6;

// The LMDB name of a database ("meta", "tiles", "top", "progress", "preview", "tileinfo"); FORMAT.
const char* database_name(Database db);

// View a string key (e.g. of `meta`) as bytes. The view aliases `text`.
inline std::span<const uint8_t> as_bytes(std::string_view text) {
  return {reinterpret_cast<const uint8_t*>(text.data()), text.size()};
}

class Store {
 public:
  enum class Mode { read_only, read_write };
  struct Options {
    Mode mode = Mode::read_only;
    // read_write: map size of a new store, or the minimum for an existing one (an existing store
    // keeps its recorded size if larger). Ignored in read_only, which uses the recorded size.
    uint64_t initial_map_size = 1ull << 30;
    bool no_sync = false;                   // read_write: MDB_NOSYNC
    unsigned max_readers = 126;             // reader slots, fixed when the lock file is created
    uint64_t max_map_size = 1ull << 40;     // growth beyond this → out_of_space
    bool no_readahead = false;              // MDB_NORDAHEAD, for stores larger than RAM
    std::chrono::milliseconds resize_wait{10000};  // how long growth waits for open transactions
  };

  // Opens (read_write: creates if needed, including the directory) the store in `dir`.
  static Result<std::unique_ptr<Store>> open(const std::filesystem::path& dir,
                                             const Options& options);
  // Precondition: no Snapshot of this store is alive. Syncs first when opened with no_sync.
  ~Store();
  Store(const Store&) = delete;
  Store& operator=(const Store&) = delete;

  struct Put {
    Database db;
    std::vector<uint8_t> key;
    std::vector<uint8_t> value;
  };
  struct Delete {
    Database db;
    std::vector<uint8_t> key;
  };

  // One atomic write transaction: all puts (overwriting), then all deletes (a missing key is not an
  // error), committed together or not at all. Keys must be 1..max_key_size() bytes.
  Status write(std::span<const Put> puts, std::span<const Delete> deletes = {});
  // Empties one database, atomically.
  Status clear(Database db);
  // Bulk load (a merge): one transaction of puts with MDB_APPEND, which skips the B-tree search and
  // fills pages densely. Within each database the keys must ascend and exceed every key already
  // there; otherwise nothing is written and the error (invalid_input) says so.
  Status append(std::span<const Put> puts);

  // A copy of the value under `key`, or nullopt; runs in its own read transaction.
  Result<std::optional<std::vector<uint8_t>>> get(Database db, std::span<const uint8_t> key) const;

  // Calls `visit` for every key starting with `prefix` (empty: all keys), in key (memcmp) order,
  // inside one read transaction. The spans are valid only during the call. `visit` returns false
  // to stop early; it must not call write() or clear() (it holds a transaction open).
  using Visitor =
      std::function<bool(std::span<const uint8_t> key, std::span<const uint8_t> value)>;
  Status for_each(Database db, std::span<const uint8_t> prefix, const Visitor& visit) const;

  // Like for_each over all keys, but starting at the first key greater than `after` (empty: the
  // first key), for reading a database in chunks of short transactions.
  Status for_each_after(Database db, std::span<const uint8_t> after, const Visitor& visit) const;
  // The greatest key of a database, or nullopt when it is empty (where an append resumes).
  Result<std::optional<std::vector<uint8_t>>> last_key(Database db) const;

  // Number of entries in a database.
  Result<uint64_t> entry_count(Database db) const;

  // A consistent read view across several reads: later writes are invisible to it. Holds an LMDB
  // read transaction (pinning old pages, delaying map growth) until destroyed, so keep it short.
  // Must not outlive the Store. Not for concurrent use by several threads; may move between
  // threads (MDB_NOTLS).
  class Snapshot {
   public:
    Snapshot(Snapshot&& other) noexcept;
    Snapshot& operator=(Snapshot&& other) noexcept;
    ~Snapshot();

    Result<std::optional<std::vector<uint8_t>>> get(Database db,
                                                    std::span<const uint8_t> key) const;
    // Zero-copy: the span points into the map and stays valid while this Snapshot lives.
    Result<std::optional<std::span<const uint8_t>>> get_view(Database db,
                                                             std::span<const uint8_t> key) const;
    Status for_each(Database db, std::span<const uint8_t> prefix, const Visitor& visit) const;

   private:
    friend class Store;
    Snapshot(const Store* store, MDB_txn* txn) : store_(store), txn_(txn) {}
    void release();
    const Store* store_;
    MDB_txn* txn_;
  };
  Result<Snapshot> snapshot() const;

  // Flushes to disk (mdb_env_sync force); needed after writes with no_sync. No-op in read_only.
  Status sync();
  // Writes a compacted copy (free pages dropped, like `mdb_copy -c`) to `target_dir`, which is
  // created if needed and must not already hold a store (→ invalid_input).
  Status compact_copy(const std::filesystem::path& target_dir) const;

  uint64_t map_size() const { return map_size_.load(std::memory_order_relaxed); }
  size_t max_key_size() const { return max_key_size_; }
  Mode mode() const { return mode_; }
  const std::filesystem::path& path() const { return path_; }

 private:
  Store(std::filesystem::path path, const Options& options);
  Status open_env();
  Status open_databases();
  Result<MDB_txn*> begin_read() const;  // enters gate_ shared; end_read leaves it
  void end_read(MDB_txn* txn) const;
  Status adopt_map_size() const;        // after MDB_MAP_RESIZED
  Status grow_map();
  Status run_write(const char* what, const std::function<int(MDB_txn*)>& body);
  Error lmdb_error(const char* what, int rc) const;

  std::filesystem::path path_;
  Options options_;
  Mode mode_;
  MDB_env* env_ = nullptr;  // closed by the destructor, even after a failed mdb_env_open
  bool env_opened_ = false;
  unsigned int dbis_[kDatabaseCount] = {};  // MDB_dbi
  bool dbi_open_[kDatabaseCount] = {};      // false: absent in a read-only store (reads as empty)
  size_t max_key_size_ = 0;
  mutable std::atomic<uint64_t> map_size_{0};
  std::mutex write_mutex_;
  mutable detail::TxnGate gate_;
};

}  // namespace shadowtiles::store
