#include "store/lmdb_store.hpp"

#include <lmdb.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cassert>
#include <cerrno>
#include <cstring>
#include <string>
#include <system_error>

namespace shadowtiles::store {

namespace {

constexpr unsigned kMaxDbs = 8;                 // room for databases added later
constexpr int kMaxMapResizedRetries = 8;        // another process may keep growing the map
constexpr std::array<Database, kDatabaseCount> kAllDatabases = {
    Database::meta, Database::tiles, Database::top, Database::progress, Database::preview, Database::tileinfo};

size_t index_of(Database db) { return static_cast<size_t>(db); }

uint64_t page_size() {
  const long size = sysconf(_SC_PAGESIZE);
  return size > 0 ? static_cast<uint64_t>(size) : 4096;
}

uint64_t round_up_to_page(uint64_t bytes) {
  const uint64_t page = page_size();
  return (bytes + page - 1) / page * page;
}

MDB_val to_val(std::span<const uint8_t> bytes) {
  // LMDB takes non-const pointers but does not write through them for keys and put values.
  return MDB_val{bytes.size(), const_cast<uint8_t*>(bytes.data())};
}

std::span<const uint8_t> from_val(const MDB_val& val) {
  return {static_cast<const uint8_t*>(val.mv_data), val.mv_size};
}

bool has_prefix(std::span<const uint8_t> key, std::span<const uint8_t> prefix) {
  return key.size() >= prefix.size() &&
         (prefix.empty() || std::memcmp(key.data(), prefix.data(), prefix.size()) == 0);
}

ErrorCode code_for(int rc) {
  switch (rc) {
    case MDB_MAP_FULL:
    case ENOSPC:
    case EDQUOT:
      return ErrorCode::out_of_space;
    case MDB_INVALID:
    case MDB_CORRUPTED:
    case MDB_PAGE_NOTFOUND:
    case MDB_PANIC:
      return ErrorCode::corrupt_data;
    case MDB_VERSION_MISMATCH:
    case MDB_INCOMPATIBLE:
      return ErrorCode::unsupported;
    case ENOENT:
    case MDB_NOTFOUND:
      return ErrorCode::not_found;
    case MDB_BAD_VALSIZE:
    case MDB_TXN_FULL:
      return ErrorCode::invalid_input;
    default:
      return ErrorCode::io_error;
  }
}

// Closes a cursor on every path out of a scope (read-only cursors are not freed by their txn).
struct CursorCloser {
  MDB_cursor* cursor;
  ~CursorCloser() { mdb_cursor_close(cursor); }
};

Result<std::optional<std::span<const uint8_t>>> txn_get(MDB_txn* txn, unsigned dbi, bool open,
                                                         std::span<const uint8_t> key) {
  if (!open) return std::optional<std::span<const uint8_t>>{};
  if (key.empty()) return make_error(ErrorCode::invalid_input, "empty key");
  MDB_val k = to_val(key);
  MDB_val v{};
  const int rc = mdb_get(txn, dbi, &k, &v);
  if (rc == MDB_NOTFOUND) return std::optional<std::span<const uint8_t>>{};
  // A key longer than LMDB allows simply cannot be stored: report it as absent.
  if (rc == MDB_BAD_VALSIZE) return std::optional<std::span<const uint8_t>>{};
  if (rc != MDB_SUCCESS) {
    return make_error(code_for(rc), std::string("lmdb get: ") + mdb_strerror(rc));
  }
  return std::optional<std::span<const uint8_t>>(from_val(v));
}

Status txn_for_each(MDB_txn* txn, unsigned dbi, bool open, std::span<const uint8_t> prefix,
                    const Store::Visitor& visit) {
  if (!open) return Status::success();
  MDB_cursor* cursor = nullptr;
  int rc = mdb_cursor_open(txn, dbi, &cursor);
  if (rc != MDB_SUCCESS) {
    return make_error(code_for(rc), std::string("lmdb cursor: ") + mdb_strerror(rc));
  }
  CursorCloser closer{cursor};
  MDB_val k = to_val(prefix);
  MDB_val v{};
  rc = prefix.empty() ? mdb_cursor_get(cursor, &k, &v, MDB_FIRST)
                      : mdb_cursor_get(cursor, &k, &v, MDB_SET_RANGE);
  while (rc == MDB_SUCCESS) {
    const std::span<const uint8_t> key = from_val(k);
    if (!has_prefix(key, prefix)) return Status::success();  // keys are sorted: past the range
    if (!visit(key, from_val(v))) return Status::success();
    rc = mdb_cursor_get(cursor, &k, &v, MDB_NEXT);
  }
  // A prefix longer than the key limit has no matches.
  if (rc == MDB_NOTFOUND || rc == MDB_BAD_VALSIZE) return Status::success();
  return make_error(code_for(rc), std::string("lmdb cursor: ") + mdb_strerror(rc));
}

std::optional<std::vector<uint8_t>> copy_out(const std::optional<std::span<const uint8_t>>& view) {
  if (!view) return std::nullopt;
  return std::vector<uint8_t>(view->begin(), view->end());
}

}  // namespace

const char* database_name(Database db) {
  switch (db) {
    case Database::meta: return "meta";
    case Database::tiles: return "tiles";
    case Database::top: return "top";
    case Database::progress: return "progress";
    case Database::preview: return "preview";
    case Database::tileinfo: return "tileinfo";
  }
  assert(false && "database_name: not a Database enumerator");
  return "unknown";
}

// ---------------------------------------------------------------------------------------------
// Open and close

Store::Store(std::filesystem::path path, const Options& options)
    : path_(std::move(path)), options_(options), mode_(options.mode) {}

Store::~Store() {
  if (!env_) return;
  assert(gate_.shared_count() == 0 && "a Snapshot outlived its Store");
  // With MDB_NOSYNC, commits may still sit in the page cache; flush them once here.
  if (env_opened_ && mode_ == Mode::read_write && options_.no_sync) mdb_env_sync(env_, 1);
  mdb_env_close(env_);
}

Error Store::lmdb_error(const char* what, int rc) const {
  // A full file system often reaches LMDB as a short write, which it reports as EIO, not ENOSPC.
  // Name the real cause when the store's file system has (next to) nothing left.
  if (rc == EIO || rc == ENOSPC || rc == EDQUOT) {
    struct statvfs fs {};
    if (::statvfs(path_.c_str(), &fs) == 0) {
      const uint64_t free_bytes = uint64_t(fs.f_bavail) * fs.f_frsize;
      if (rc != EIO || free_bytes < (uint64_t{1} << 20))
        return make_error(ErrorCode::out_of_space,
                          "store " + path_.string() + ": " + what + ": the disk is full (" +
                              std::to_string(free_bytes) + " bytes free on its file system; " + mdb_strerror(rc) +
                              "); the store keeps every committed record: free space and rerun to resume");
    }
  }
  return make_error(code_for(rc),
                    std::string("store ") + path_.string() + ": " + what + ": " + mdb_strerror(rc));
}

Result<std::unique_ptr<Store>> Store::open(const std::filesystem::path& dir,
                                           const Options& options) {
  std::unique_ptr<Store> store(new Store(dir, options));
  if (Status status = store->open_env(); !status) return status.error();
  if (Status status = store->open_databases(); !status) return status.error();
  return store;
}

Status Store::open_env() {
  const bool read_only = mode_ == Mode::read_only;
  const std::filesystem::path data_file = path_ / "data.mdb";
  std::error_code ec;
  bool exists = std::filesystem::exists(data_file, ec);
  if (read_only && !exists) {
    return make_error(ErrorCode::not_found, "store " + path_.string() + ": no LMDB store there");
  }
  if (!read_only) {
    std::filesystem::create_directories(path_, ec);
    if (ec) {
      return make_error(ErrorCode::io_error,
                        "store " + path_.string() + ": cannot create directory: " + ec.message());
    }
  }

  int rc = mdb_env_create(&env_);
  if (rc != MDB_SUCCESS) {
    env_ = nullptr;
    return lmdb_error("mdb_env_create", rc);
  }
  if ((rc = mdb_env_set_maxdbs(env_, kMaxDbs)) != MDB_SUCCESS) {
    return lmdb_error("mdb_env_set_maxdbs", rc);
  }
  if ((rc = mdb_env_set_maxreaders(env_, options_.max_readers)) != MDB_SUCCESS) {
    return lmdb_error("mdb_env_set_maxreaders", rc);
  }
  // A configured size overrides the recorded one at open (even when smaller), so only configure it
  // for a new store; an existing one is raised to initial_map_size after opening.
  const uint64_t initial = round_up_to_page(options_.initial_map_size);
  if (!read_only && !exists) {
    if ((rc = mdb_env_set_mapsize(env_, initial)) != MDB_SUCCESS) {
      return lmdb_error("mdb_env_set_mapsize", rc);
    }
  }

  // NOTLS: read transactions are not bound to threads (thread pools, movable Snapshots).
  unsigned flags = MDB_NOTLS;
  if (read_only) flags |= MDB_RDONLY;
  if (!read_only && options_.no_sync) flags |= MDB_NOSYNC;
  if (options_.no_readahead) flags |= MDB_NORDAHEAD;
  rc = mdb_env_open(env_, path_.c_str(), flags, 0644);
  if (rc != MDB_SUCCESS) {
    if (rc == ENOENT) {
      return make_error(ErrorCode::not_found, "store " + path_.string() + ": no LMDB store there");
    }
    return lmdb_error("mdb_env_open", rc);
  }
  env_opened_ = true;

  // Reader slots left by crashed processes pin old pages and use up slots.
  int dead = 0;
  if ((rc = mdb_reader_check(env_, &dead)) != MDB_SUCCESS) return lmdb_error("mdb_reader_check", rc);

  MDB_envinfo info{};
  if ((rc = mdb_env_info(env_, &info)) != MDB_SUCCESS) return lmdb_error("mdb_env_info", rc);
  if (!read_only && info.me_mapsize < initial) {
    if ((rc = mdb_env_set_mapsize(env_, initial)) != MDB_SUCCESS) {
      return lmdb_error("mdb_env_set_mapsize", rc);
    }
    if ((rc = mdb_env_info(env_, &info)) != MDB_SUCCESS) return lmdb_error("mdb_env_info", rc);
  }
  map_size_.store(info.me_mapsize);
  max_key_size_ = static_cast<size_t>(mdb_env_get_maxkeysize(env_));
  return Status::success();
}

Status Store::open_databases() {
  const bool read_only = mode_ == Mode::read_only;
  // Handles opened inside a transaction become usable by all transactions once it commits.
  for (int attempt = 0;; ++attempt) {
    MDB_txn* txn = nullptr;
    int rc = mdb_txn_begin(env_, nullptr, read_only ? MDB_RDONLY : 0, &txn);
    if (rc == MDB_MAP_RESIZED && attempt < kMaxMapResizedRetries) {
      if (Status status = adopt_map_size(); !status) return status;
      continue;
    }
    if (rc != MDB_SUCCESS) return lmdb_error("mdb_txn_begin", rc);
    for (Database db : kAllDatabases) {
      const size_t i = index_of(db);
      rc = mdb_dbi_open(txn, database_name(db), read_only ? 0 : MDB_CREATE, &dbis_[i]);
      if (rc == MDB_NOTFOUND && read_only && db != Database::meta) {
        dbi_open_[i] = false;  // reads as empty
        continue;
      }
      if (rc != MDB_SUCCESS) {
        mdb_txn_abort(txn);
        if (rc == MDB_NOTFOUND) {
          return make_error(ErrorCode::not_found,
                            "store " + path_.string() + ": no '" + database_name(db) +
                                "' database, not a shadowtiles store");
        }
        // Retrying with a bigger map is write()'s job; creating 4 databases fits any sane size.
        return lmdb_error("mdb_dbi_open", rc);
      }
      dbi_open_[i] = true;
    }
    if ((rc = mdb_txn_commit(txn)) != MDB_SUCCESS) return lmdb_error("mdb_txn_commit", rc);
    return Status::success();
  }
}

// ---------------------------------------------------------------------------------------------
// Map size

Status Store::adopt_map_size() const {
  if (!gate_.enter_exclusive(options_.resize_wait)) {
    return make_error(ErrorCode::io_error,
                      "store " + path_.string() +
                          ": another process grew the map, and open transactions here kept it "
                          "from being remapped");
  }
  // Size 0: take the size another process recorded.
  int rc = mdb_env_set_mapsize(env_, 0);
  MDB_envinfo info{};
  if (rc == MDB_SUCCESS) rc = mdb_env_info(env_, &info);
  if (rc == MDB_SUCCESS) map_size_.store(info.me_mapsize);
  gate_.leave_exclusive();
  if (rc != MDB_SUCCESS) return lmdb_error("mdb_env_set_mapsize", rc);
  return Status::success();
}

Status Store::grow_map() {
  const uint64_t current = map_size();
  const uint64_t cap = options_.max_map_size;
  if (current >= cap) {
    return make_error(ErrorCode::out_of_space,
                      "store " + path_.string() + ": map full at " + std::to_string(current) +
                          " bytes (max_map_size " + std::to_string(cap) + ")");
  }
  const uint64_t next = round_up_to_page(std::min(current * 2, cap));
  if (!gate_.enter_exclusive(options_.resize_wait)) {
    return make_error(ErrorCode::io_error,
                      "store " + path_.string() +
                          ": map full and cannot grow while read transactions stay open in this "
                          "process (a Snapshot held across write()?)");
  }
  int rc = mdb_env_set_mapsize(env_, next);
  if (rc != MDB_SUCCESS) {
    // The old mapping is gone; try to get it back so the store stays usable.
    mdb_env_set_mapsize(env_, current);
  }
  MDB_envinfo info{};
  if (mdb_env_info(env_, &info) == MDB_SUCCESS) map_size_.store(info.me_mapsize);
  gate_.leave_exclusive();
  if (rc != MDB_SUCCESS) {
    // mmap refusing a bigger size means address space or memory, not a bug in the data.
    Error error = lmdb_error("growing the map", rc);
    if (rc == ENOMEM) error.code = ErrorCode::out_of_space;
    return error;
  }
  return Status::success();
}

// ---------------------------------------------------------------------------------------------
// Writes

Status Store::run_write(const char* what, const std::function<int(MDB_txn*)>& body) {
  if (mode_ != Mode::read_write) {
    return make_error(ErrorCode::invalid_input,
                      "store " + path_.string() + ": " + what + " on a read-only store");
  }
  std::lock_guard write_lock(write_mutex_);
  for (int resized = 0;;) {
    gate_.enter_shared();
    MDB_txn* txn = nullptr;
    int rc = mdb_txn_begin(env_, nullptr, 0, &txn);
    if (rc == MDB_SUCCESS) {
      rc = body(txn);
      if (rc == MDB_SUCCESS) {
        rc = mdb_txn_commit(txn);  // frees txn whatever the outcome; a failure leaves no trace
      } else {
        mdb_txn_abort(txn);
      }
    }
    gate_.leave_shared();
    if (rc == MDB_SUCCESS) return Status::success();
    if (rc == MDB_MAP_FULL) {
      if (Status grown = grow_map(); !grown) return grown;
      continue;
    }
    if (rc == MDB_MAP_RESIZED && resized++ < kMaxMapResizedRetries) {
      if (Status adopted = adopt_map_size(); !adopted) return adopted;
      continue;
    }
    return lmdb_error(what, rc);
  }
}

Status Store::write(std::span<const Put> puts, std::span<const Delete> deletes) {
  const auto check_key = [&](const std::vector<uint8_t>& key) -> Status {
    if (key.empty() || key.size() > max_key_size_) {
      return make_error(ErrorCode::invalid_input,
                        "store " + path_.string() + ": key of " + std::to_string(key.size()) +
                            " bytes (allowed 1.." + std::to_string(max_key_size_) + ")");
    }
    return Status::success();
  };
  for (const Put& put : puts) {
    if (Status status = check_key(put.key); !status) return status;
  }
  for (const Delete& del : deletes) {
    if (Status status = check_key(del.key); !status) return status;
  }
  if (puts.empty() && deletes.empty() && mode_ == Mode::read_write) return Status::success();
  return run_write("write", [&](MDB_txn* txn) {
    for (const Put& put : puts) {
      MDB_val k = to_val(put.key);
      MDB_val v = to_val(put.value);
      const int rc = mdb_put(txn, dbis_[index_of(put.db)], &k, &v, 0);
      if (rc != MDB_SUCCESS) return rc;
    }
    for (const Delete& del : deletes) {
      MDB_val k = to_val(del.key);
      const int rc = mdb_del(txn, dbis_[index_of(del.db)], &k, nullptr);
      if (rc != MDB_SUCCESS && rc != MDB_NOTFOUND) return rc;
    }
    return MDB_SUCCESS;
  });
}

Status Store::append(std::span<const Put> puts) {
  for (const Put& put : puts) {
    if (put.key.empty() || put.key.size() > max_key_size_) {
      return make_error(ErrorCode::invalid_input,
                        "store " + path_.string() + ": key of " + std::to_string(put.key.size()) +
                            " bytes (allowed 1.." + std::to_string(max_key_size_) + ")");
    }
  }
  if (puts.empty() && mode_ == Mode::read_write) return Status::success();
  bool out_of_order = false;
  Status status = run_write("append", [&](MDB_txn* txn) {
    for (const Put& put : puts) {
      MDB_val k = to_val(put.key);
      MDB_val v = to_val(put.value);
      const int rc = mdb_put(txn, dbis_[index_of(put.db)], &k, &v, MDB_APPEND);
      out_of_order = rc == MDB_KEYEXIST;  // LMDB's answer to an append below the last key
      if (rc != MDB_SUCCESS) return rc;
    }
    return MDB_SUCCESS;
  });
  if (!status && out_of_order) {
    return make_error(ErrorCode::invalid_input,
                      "store " + path_.string() + ": append with a key not above the database's last key");
  }
  return status;
}

Status Store::clear(Database db) {
  return run_write("clear", [&](MDB_txn* txn) { return mdb_drop(txn, dbis_[index_of(db)], 0); });
}

Status Store::sync() {
  if (mode_ == Mode::read_only) return Status::success();
  // Shared, as a transaction: the sync reads the current meta page from the map, which a growth
  // (exclusive) may remap. Writers may commit meanwhile (the build syncs while its workers write).
  gate_.enter_shared();
  const int rc = mdb_env_sync(env_, 1);
  gate_.leave_shared();
  if (rc != MDB_SUCCESS) return lmdb_error("mdb_env_sync", rc);
  return Status::success();
}

// ---------------------------------------------------------------------------------------------
// Reads

Result<MDB_txn*> Store::begin_read() const {
  for (int attempt = 0;; ++attempt) {
    gate_.enter_shared();
    MDB_txn* txn = nullptr;
    const int rc = mdb_txn_begin(env_, nullptr, MDB_RDONLY, &txn);
    if (rc == MDB_SUCCESS) return txn;
    gate_.leave_shared();
    if (rc == MDB_MAP_RESIZED && attempt < kMaxMapResizedRetries) {
      if (Status status = adopt_map_size(); !status) return status.error();
      continue;
    }
    return lmdb_error("mdb_txn_begin", rc);
  }
}

void Store::end_read(MDB_txn* txn) const {
  mdb_txn_abort(txn);
  gate_.leave_shared();
}

Result<std::optional<std::vector<uint8_t>>> Store::get(Database db,
                                                       std::span<const uint8_t> key) const {
  Result<MDB_txn*> txn = begin_read();
  if (!txn) return txn.error();
  const size_t i = index_of(db);
  Result<std::optional<std::span<const uint8_t>>> view = txn_get(*txn, dbis_[i], dbi_open_[i], key);
  Result<std::optional<std::vector<uint8_t>>> result =
      view ? Result<std::optional<std::vector<uint8_t>>>(copy_out(*view))
           : Result<std::optional<std::vector<uint8_t>>>(view.error());
  end_read(*txn);
  return result;
}

Status Store::for_each(Database db, std::span<const uint8_t> prefix, const Visitor& visit) const {
  Result<MDB_txn*> txn = begin_read();
  if (!txn) return txn.error();
  const size_t i = index_of(db);
  Status status;
  try {
    status = txn_for_each(*txn, dbis_[i], dbi_open_[i], prefix, visit);
  } catch (...) {
    end_read(*txn);  // a throwing visitor must not leak the transaction
    throw;
  }
  end_read(*txn);
  return status;
}

Status Store::for_each_after(Database db, std::span<const uint8_t> after, const Visitor& visit) const {
  const size_t i = index_of(db);
  if (!dbi_open_[i]) return Status::success();
  Result<MDB_txn*> txn = begin_read();
  if (!txn) return txn.error();
  MDB_cursor* cursor = nullptr;
  int rc = mdb_cursor_open(*txn, dbis_[i], &cursor);
  if (rc != MDB_SUCCESS) {
    end_read(*txn);
    return lmdb_error("mdb_cursor_open", rc);
  }
  MDB_val k = to_val(after);
  MDB_val v{};
  rc = after.empty() ? mdb_cursor_get(cursor, &k, &v, MDB_FIRST) : mdb_cursor_get(cursor, &k, &v, MDB_SET_RANGE);
  if (rc == MDB_SUCCESS && !after.empty() && from_val(k).size() == after.size() &&
      std::memcmp(k.mv_data, after.data(), after.size()) == 0) {
    rc = mdb_cursor_get(cursor, &k, &v, MDB_NEXT);
  }
  try {
    while (rc == MDB_SUCCESS) {
      if (!visit(from_val(k), from_val(v))) { rc = MDB_NOTFOUND; break; }
      rc = mdb_cursor_get(cursor, &k, &v, MDB_NEXT);
    }
  } catch (...) {
    mdb_cursor_close(cursor);
    end_read(*txn);
    throw;
  }
  mdb_cursor_close(cursor);
  end_read(*txn);
  if (rc == MDB_NOTFOUND) return Status::success();
  return lmdb_error("cursor", rc);
}

Result<std::optional<std::vector<uint8_t>>> Store::last_key(Database db) const {
  const size_t i = index_of(db);
  if (!dbi_open_[i]) return std::optional<std::vector<uint8_t>>{};
  Result<MDB_txn*> txn = begin_read();
  if (!txn) return txn.error();
  MDB_cursor* cursor = nullptr;
  int rc = mdb_cursor_open(*txn, dbis_[i], &cursor);
  std::optional<std::vector<uint8_t>> last;
  if (rc == MDB_SUCCESS) {
    MDB_val k{}, v{};
    rc = mdb_cursor_get(cursor, &k, &v, MDB_LAST);
    if (rc == MDB_SUCCESS) last = std::vector<uint8_t>(from_val(k).begin(), from_val(k).end());
    mdb_cursor_close(cursor);
  }
  end_read(*txn);
  if (rc != MDB_SUCCESS && rc != MDB_NOTFOUND) return lmdb_error("mdb_cursor_get last", rc);
  return last;
}

Result<uint64_t> Store::entry_count(Database db) const {
  const size_t i = index_of(db);
  if (!dbi_open_[i]) return uint64_t{0};
  Result<MDB_txn*> txn = begin_read();
  if (!txn) return txn.error();
  MDB_stat stat{};
  const int rc = mdb_stat(*txn, dbis_[i], &stat);
  end_read(*txn);
  if (rc != MDB_SUCCESS) return lmdb_error("mdb_stat", rc);
  return static_cast<uint64_t>(stat.ms_entries);
}

Result<Store::Snapshot> Store::snapshot() const {
  Result<MDB_txn*> txn = begin_read();
  if (!txn) return txn.error();
  return Snapshot(this, *txn);
}

Status Store::compact_copy(const std::filesystem::path& target_dir) const {
  std::error_code ec;
  std::filesystem::create_directories(target_dir, ec);
  if (ec) {
    return make_error(ErrorCode::io_error,
                      "compact copy: cannot create " + target_dir.string() + ": " + ec.message());
  }
  if (std::filesystem::exists(target_dir / "data.mdb", ec)) {
    return make_error(ErrorCode::invalid_input,
                      "compact copy: " + target_dir.string() + " already holds a store");
  }
  // The copy runs its own read transaction: hold the gate so the map is not replaced under it.
  gate_.enter_shared();
  const int rc = mdb_env_copy2(env_, target_dir.c_str(), MDB_CP_COMPACT);
  gate_.leave_shared();
  if (rc != MDB_SUCCESS) return lmdb_error("mdb_env_copy2", rc);
  return Status::success();
}

// ---------------------------------------------------------------------------------------------
// Snapshot

Store::Snapshot::Snapshot(Snapshot&& other) noexcept : store_(other.store_), txn_(other.txn_) {
  other.txn_ = nullptr;
}

Store::Snapshot& Store::Snapshot::operator=(Snapshot&& other) noexcept {
  if (this != &other) {
    release();
    store_ = other.store_;
    txn_ = other.txn_;
    other.txn_ = nullptr;
  }
  return *this;
}

Store::Snapshot::~Snapshot() { release(); }

void Store::Snapshot::release() {
  if (txn_) store_->end_read(txn_);
  txn_ = nullptr;
}

Result<std::optional<std::span<const uint8_t>>> Store::Snapshot::get_view(
    Database db, std::span<const uint8_t> key) const {
  assert(txn_ && "use of a moved-from Snapshot");
  const size_t i = index_of(db);
  return txn_get(txn_, store_->dbis_[i], store_->dbi_open_[i], key);
}

Result<std::optional<std::vector<uint8_t>>> Store::Snapshot::get(
    Database db, std::span<const uint8_t> key) const {
  Result<std::optional<std::span<const uint8_t>>> view = get_view(db, key);
  if (!view) return view.error();
  return copy_out(*view);
}

Status Store::Snapshot::for_each(Database db, std::span<const uint8_t> prefix,
                                 const Visitor& visit) const {
  assert(txn_ && "use of a moved-from Snapshot");
  const size_t i = index_of(db);
  return txn_for_each(txn_, store_->dbis_[i], store_->dbi_open_[i], prefix, visit);
}

}  // namespace shadowtiles::store
