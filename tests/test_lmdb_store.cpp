#include "store/lmdb_store.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstring>
#include <map>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "store/tile_key.hpp"
#include "tests/testing_support.hpp"

namespace shadowtiles::store {
namespace {

using testing::TempDir;
using Bytes = std::vector<uint8_t>;

Bytes bytes_of(std::string_view text) { return Bytes(text.begin(), text.end()); }

Bytes tile_key(uint8_t level, uint32_t x, uint32_t y, Method method = Method::mh) {
  const auto key = encode_tile_key({method, level, x, y});
  return Bytes(key.begin(), key.end());
}

Bytes value_for(uint64_t seed, size_t size) {
  std::mt19937_64 rng(seed);
  Bytes value(size);
  for (auto& byte : value) byte = static_cast<uint8_t>(rng());
  return value;
}

Store::Options rw_options() {
  Store::Options options;
  options.mode = Store::Mode::read_write;
  options.initial_map_size = 1 << 20;
  return options;
}

std::unique_ptr<Store> open_or_die(const std::filesystem::path& dir, const Store::Options& options) {
  Result<std::unique_ptr<Store>> store = Store::open(dir, options);
  EXPECT_TRUE(store.ok()) << (store.ok() ? "" : store.error().message);
  if (!store.ok()) return nullptr;
  return std::move(store).value();
}

// LMDB's default key order: memcmp over the common length, then shorter first.
struct MemcmpLess {
  bool operator()(const Bytes& a, const Bytes& b) const {
    const size_t common = std::min(a.size(), b.size());
    const int cmp = common == 0 ? 0 : std::memcmp(a.data(), b.data(), common);
    return cmp != 0 ? cmp < 0 : a.size() < b.size();
  }
};

std::optional<Bytes> get_or_die(const Store& store, Database db, std::span<const uint8_t> key) {
  auto value = store.get(db, key);
  EXPECT_TRUE(value.ok()) << (value.ok() ? "" : value.error().message);
  return value.ok() ? *value : std::nullopt;
}

TEST(LmdbStore, RoundTripAcrossReopen) {
  TempDir dir;
  const auto path = dir.path() / "store";
  {
    auto store = open_or_die(path, rw_options());
    ASSERT_TRUE(store);
    std::vector<Store::Put> puts = {
        {Database::meta, bytes_of("scene"), bytes_of("{\"name\":\"test\"}")},
        {Database::tiles, tile_key(0, 0, 0), value_for(1, 1000)},
        {Database::top, bytes_of("skiplist"), value_for(2, 10)},
        {Database::progress, bytes_of("done"), Bytes{}},  // empty values are fine
    };
    ASSERT_TRUE(store->write(puts).ok());
    // Overwrite and delete in one transaction.
    std::vector<Store::Put> overwrite = {{Database::tiles, tile_key(0, 0, 0), value_for(3, 5)}};
    std::vector<Store::Delete> deletes = {{Database::top, bytes_of("skiplist")},
                                          {Database::top, bytes_of("never-there")}};
    ASSERT_TRUE(store->write(overwrite, deletes).ok());
    // Same key in meta and tiles is independent.
    EXPECT_FALSE(get_or_die(*store, Database::tiles, as_bytes("scene")));
  }
  Store::Options ro;
  auto store = open_or_die(path, ro);
  ASSERT_TRUE(store);
  EXPECT_EQ(store->mode(), Store::Mode::read_only);
  EXPECT_EQ(get_or_die(*store, Database::meta, as_bytes("scene")), bytes_of("{\"name\":\"test\"}"));
  EXPECT_EQ(get_or_die(*store, Database::tiles, tile_key(0, 0, 0)), value_for(3, 5));
  EXPECT_FALSE(get_or_die(*store, Database::top, as_bytes("skiplist")));
  EXPECT_EQ(get_or_die(*store, Database::progress, as_bytes("done")), Bytes{});
  EXPECT_FALSE(get_or_die(*store, Database::meta, as_bytes("absent")));
  EXPECT_EQ(*store->entry_count(Database::tiles), 1u);

  // Read-only stores refuse writes.
  std::vector<Store::Put> put = {{Database::meta, bytes_of("k"), bytes_of("v")}};
  Status status = store->write(put);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.error().code, ErrorCode::invalid_input);
  EXPECT_FALSE(store->clear(Database::meta).ok());
  EXPECT_TRUE(store->sync().ok());
}

TEST(LmdbStore, InvalidKeysAreRejected) {
  TempDir dir;
  auto store = open_or_die(dir.path(), rw_options());
  ASSERT_TRUE(store);
  std::vector<Store::Put> empty_key = {{Database::meta, Bytes{}, bytes_of("v")}};
  EXPECT_EQ(store->write(empty_key).error().code, ErrorCode::invalid_input);
  std::vector<Store::Put> long_key = {
      {Database::meta, Bytes(store->max_key_size() + 1, 'k'), bytes_of("v")}};
  EXPECT_EQ(store->write(long_key).error().code, ErrorCode::invalid_input);
  // Nothing of a rejected batch is written.
  std::vector<Store::Put> mixed = {{Database::meta, bytes_of("ok"), bytes_of("v")},
                                   {Database::meta, Bytes{}, bytes_of("v")}};
  EXPECT_FALSE(store->write(mixed).ok());
  EXPECT_FALSE(get_or_die(*store, Database::meta, as_bytes("ok")));
  EXPECT_FALSE(get_or_die(*store, Database::meta, Bytes(store->max_key_size() + 1, 'k')));
}

TEST(LmdbStore, ForEachPrefixInKeyOrder) {
  TempDir dir;
  auto store = open_or_die(dir.path(), rw_options());
  ASSERT_TRUE(store);
  std::mt19937_64 rng(5);
  std::map<Bytes, Bytes, MemcmpLess> expected_level2;
  std::vector<Store::Put> puts;
  for (int i = 0; i < 500; ++i) {
    const uint8_t level = static_cast<uint8_t>(rng() % 4);
    const Method method = rng() % 2 ? Method::mh : Method::dagmh;
    const uint32_t x = static_cast<uint32_t>(rng() % 300);
    const uint32_t y = static_cast<uint32_t>(rng() % 70000);
    Bytes key = tile_key(level, x, y, method);
    Bytes value = value_for(static_cast<uint64_t>(i), 8);
    if (method == Method::mh && level == 2) expected_level2[key] = value;
    puts.push_back({Database::tiles, std::move(key), std::move(value)});
  }
  ASSERT_TRUE(store->write(puts).ok());

  const auto prefix = tile_key_prefix(Method::mh, 2);
  std::vector<std::pair<Bytes, Bytes>> seen;
  Status status = store->for_each(Database::tiles, prefix, [&](auto key, auto value) {
    seen.emplace_back(Bytes(key.begin(), key.end()), Bytes(value.begin(), value.end()));
    return true;
  });
  ASSERT_TRUE(status.ok());
  ASSERT_EQ(seen.size(), expected_level2.size());
  ASSERT_FALSE(seen.empty());
  size_t i = 0;
  TileKey previous{};
  for (const auto& [key, value] : expected_level2) {
    EXPECT_EQ(seen[i].first, key);
    EXPECT_EQ(seen[i].second, value);
    const TileKey decoded = *decode_tile_key(key);
    if (i > 0) {
      EXPECT_LT(previous, decoded);  // numeric order
    }
    previous = decoded;
    ++i;
  }

  // Early stop, empty prefix (everything), prefix with no match.
  int visited = 0;
  ASSERT_TRUE(store->for_each(Database::tiles, prefix, [&](auto, auto) { return ++visited < 3; }).ok());
  EXPECT_EQ(visited, 3);
  size_t all = 0;
  ASSERT_TRUE(store->for_each(Database::tiles, {}, [&](auto, auto) { return ++all, true; }).ok());
  EXPECT_EQ(all, *store->entry_count(Database::tiles));
  const auto none = tile_key_prefix(Method::sst, 0);
  ASSERT_TRUE(store->for_each(Database::tiles, none, [&](auto, auto) {
    ADD_FAILURE() << "unexpected key";
    return true;
  }).ok());

  // clear empties one database only.
  std::vector<Store::Put> meta = {{Database::meta, bytes_of("k"), bytes_of("v")}};
  ASSERT_TRUE(store->write(meta).ok());
  ASSERT_TRUE(store->clear(Database::tiles).ok());
  EXPECT_EQ(*store->entry_count(Database::tiles), 0u);
  EXPECT_EQ(*store->entry_count(Database::meta), 1u);
}

TEST(LmdbStore, MapGrowsFromTinyInitialSize) {
  TempDir dir;
  const auto path = dir.path() / "grow";
  Store::Options options = rw_options();
  options.initial_map_size = 64 << 10;
  options.no_sync = true;
  uint64_t initial_size = 0;
  const size_t kValue = 256 << 10;
  const int kWrites = 8, kPerWrite = 10;  // 8 * 10 * 256 KiB = 20 MiB
  {
    auto store = open_or_die(path, options);
    ASSERT_TRUE(store);
    initial_size = store->map_size();
    EXPECT_LT(initial_size, 1u << 20);
    for (int w = 0; w < kWrites; ++w) {
      std::vector<Store::Put> puts;
      for (int i = 0; i < kPerWrite; ++i) {
        const int n = w * kPerWrite + i;
        puts.push_back({Database::tiles, tile_key(5, static_cast<uint32_t>(n), 0),
                        value_for(static_cast<uint64_t>(n), kValue)});
      }
      Status status = store->write(puts);
      ASSERT_TRUE(status.ok()) << status.error().message;
    }
    EXPECT_GE(store->map_size(), uint64_t{20} << 20);
    ASSERT_TRUE(store->sync().ok());
  }
  Store::Options ro;
  auto store = open_or_die(path, ro);
  ASSERT_TRUE(store);
  EXPECT_GT(store->map_size(), initial_size);
  for (int n = 0; n < kWrites * kPerWrite; ++n) {
    auto value = get_or_die(*store, Database::tiles, tile_key(5, static_cast<uint32_t>(n), 0));
    ASSERT_TRUE(value) << n;
    EXPECT_EQ(*value, value_for(static_cast<uint64_t>(n), kValue)) << n;
  }
  // Reopening read-write with a small initial size keeps the recorded, larger map.
  store.reset();
  auto rw = open_or_die(path, options);
  ASSERT_TRUE(rw);
  EXPECT_GE(rw->map_size(), uint64_t{20} << 20);
}

TEST(LmdbStore, GrowthStopsAtTheCap) {
  TempDir dir;
  Store::Options options = rw_options();
  options.initial_map_size = 256 << 10;
  options.max_map_size = 1 << 20;
  auto store = open_or_die(dir.path(), options);
  ASSERT_TRUE(store);
  std::vector<Store::Put> small = {{Database::tiles, tile_key(0, 0, 0), value_for(1, 1000)}};
  ASSERT_TRUE(store->write(small).ok());
  std::vector<Store::Put> huge = {{Database::tiles, tile_key(0, 1, 0), value_for(2, 2 << 20)}};
  Status status = store->write(huge);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.error().code, ErrorCode::out_of_space) << status.error().message;
  EXPECT_LE(store->map_size(), options.max_map_size);
  // Nothing half-written, and the store still works.
  EXPECT_FALSE(get_or_die(*store, Database::tiles, tile_key(0, 1, 0)));
  EXPECT_EQ(get_or_die(*store, Database::tiles, tile_key(0, 0, 0)), value_for(1, 1000));
  std::vector<Store::Put> more = {{Database::tiles, tile_key(0, 2, 0), value_for(3, 1000)}};
  EXPECT_TRUE(store->write(more).ok());
}

TEST(LmdbStore, GrowthWithAnOpenSnapshotFailsCleanlyInsteadOfDeadlocking) {
  TempDir dir;
  Store::Options options = rw_options();
  options.initial_map_size = 64 << 10;
  options.resize_wait = std::chrono::milliseconds(100);
  auto store = open_or_die(dir.path(), options);
  ASSERT_TRUE(store);
  std::vector<Store::Put> big = {{Database::tiles, tile_key(0, 0, 0), value_for(1, 1 << 20)}};
  {
    auto snapshot = store->snapshot();
    ASSERT_TRUE(snapshot.ok());
    Status status = store->write(big);
    ASSERT_FALSE(status.ok());
    EXPECT_EQ(status.error().code, ErrorCode::io_error);
    EXPECT_FALSE(get_or_die(*store, Database::tiles, tile_key(0, 0, 0)));
  }
  EXPECT_TRUE(store->write(big).ok());  // once the snapshot is gone
}

// The merge's bulk path: MDB_APPEND in key order, refusing a key not above the last one (nothing of
// that transaction is kept), chunked reads after a key, and the last key where a resume restarts.
TEST(LmdbStore, AppendInKeyOrderAndChunkedReads) {
  TempDir dir;
  auto store = open_or_die(dir.path(), rw_options());
  ASSERT_TRUE(store);
  auto last = store->last_key(Database::tiles);
  ASSERT_TRUE(last.ok());
  EXPECT_FALSE(last->has_value());
  std::vector<Store::Put> batch;
  for (uint32_t x = 0; x < 300; ++x)
    batch.push_back({Database::tiles, tile_key(3, x, 7), value_for(x, 5000)});  // grows the 1 MiB map
  ASSERT_TRUE(store->append(batch).ok());
  last = store->last_key(Database::tiles);
  ASSERT_TRUE(last.ok() && last->has_value());
  EXPECT_EQ(**last, tile_key(3, 299, 7));

  std::vector<Store::Put> stale{{Database::tiles, tile_key(3, 300, 0), Bytes{1}},
                                {Database::tiles, tile_key(3, 5, 0), Bytes{2}}};
  Status refused = store->append(stale);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, ErrorCode::invalid_input);
  auto count = store->entry_count(Database::tiles);
  ASSERT_TRUE(count.ok());
  EXPECT_EQ(*count, 300u);  // the first put of the refused transaction is gone too

  std::vector<Bytes> seen;
  Bytes after = tile_key(3, 9, 7);
  ASSERT_TRUE(store->for_each_after(Database::tiles, after, [&](std::span<const uint8_t> key, std::span<const uint8_t> value) {
                 seen.emplace_back(key.begin(), key.end());
                 EXPECT_EQ(Bytes(value.begin(), value.end()), value_for(9 + seen.size(), 5000));
                 return seen.size() < 3;
               }).ok());
  ASSERT_EQ(seen.size(), 3u);
  EXPECT_EQ(seen[0], tile_key(3, 10, 7));
  EXPECT_EQ(seen[2], tile_key(3, 12, 7));
  // A key between stored keys starts at the next one; the empty key at the first.
  seen.clear();
  ASSERT_TRUE(store->for_each_after(Database::tiles, tile_key(3, 20, 0), [&](std::span<const uint8_t> key, std::span<const uint8_t>) {
                 seen.emplace_back(key.begin(), key.end());
                 return false;
               }).ok());
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0], tile_key(3, 20, 7));
  seen.clear();
  ASSERT_TRUE(store->for_each_after(Database::tiles, {}, [&](std::span<const uint8_t> key, std::span<const uint8_t>) {
                 seen.emplace_back(key.begin(), key.end());
                 return false;
               }).ok());
  EXPECT_EQ(seen.at(0), tile_key(3, 0, 7));
}

TEST(LmdbStore, ReadOnlyOpenOfMissingStoreIsNotFound) {
  TempDir dir;
  Store::Options ro;
  auto missing = Store::open(dir.path() / "does-not-exist", ro);
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.error().code, ErrorCode::not_found);
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "does-not-exist"));
  auto empty_dir = Store::open(dir.path(), ro);
  ASSERT_FALSE(empty_dir.ok());
  EXPECT_EQ(empty_dir.error().code, ErrorCode::not_found);
}

TEST(LmdbStore, GarbageFileIsAnErrorNotACrash) {
  TempDir dir;
  {
    std::FILE* file = std::fopen((dir.path() / "data.mdb").c_str(), "wb");
    ASSERT_TRUE(file);
    const Bytes junk = value_for(1, 64 << 10);
    std::fwrite(junk.data(), 1, junk.size(), file);
    std::fclose(file);
  }
  Store::Options ro;
  auto store = Store::open(dir.path(), ro);
  ASSERT_FALSE(store.ok());
  EXPECT_NE(store.error().message.find(dir.path().string()), std::string::npos);
}

TEST(LmdbStore, SnapshotIsolation) {
  TempDir dir;
  auto store = open_or_die(dir.path(), rw_options());
  ASSERT_TRUE(store);
  std::vector<Store::Put> first = {{Database::meta, bytes_of("k"), bytes_of("v1")}};
  ASSERT_TRUE(store->write(first).ok());

  auto old_snapshot = store->snapshot();
  ASSERT_TRUE(old_snapshot.ok());
  std::vector<Store::Put> second = {{Database::meta, bytes_of("k"), bytes_of("v2")},
                                    {Database::meta, bytes_of("new"), bytes_of("n")}};
  ASSERT_TRUE(store->write(second).ok());

  EXPECT_EQ(*old_snapshot->get(Database::meta, as_bytes("k")).value(), bytes_of("v1"));
  EXPECT_FALSE(old_snapshot->get(Database::meta, as_bytes("new")).value());
  size_t old_count = 0;
  ASSERT_TRUE(old_snapshot->for_each(Database::meta, {}, [&](auto, auto) { return ++old_count, true; }).ok());
  EXPECT_EQ(old_count, 1u);

  auto new_snapshot = store->snapshot();
  ASSERT_TRUE(new_snapshot.ok());
  EXPECT_EQ(*new_snapshot->get(Database::meta, as_bytes("k")).value(), bytes_of("v2"));
  auto view = new_snapshot->get_view(Database::meta, as_bytes("new"));
  ASSERT_TRUE(view.ok() && view->has_value());
  EXPECT_EQ(Bytes((*view)->begin(), (*view)->end()), bytes_of("n"));
  EXPECT_EQ(get_or_die(*store, Database::meta, as_bytes("k")), bytes_of("v2"));

  // Snapshots move (e.g. into another thread) and stay valid.
  Store::Snapshot moved = std::move(old_snapshot).value();
  std::thread other([&] { EXPECT_EQ(*moved.get(Database::meta, as_bytes("k")).value(), bytes_of("v1")); });
  other.join();
}

TEST(LmdbStore, CompactCopyHasSameContents) {
  TempDir dir;
  auto store = open_or_die(dir.path() / "src", rw_options());
  ASSERT_TRUE(store);
  std::vector<Store::Put> puts;
  for (uint32_t i = 0; i < 200; ++i) {
    puts.push_back({Database::tiles, tile_key(1, i, i), value_for(i, 3000)});
  }
  puts.push_back({Database::meta, bytes_of("format"), bytes_of("1")});
  ASSERT_TRUE(store->write(puts).ok());
  // Free pages to be dropped by compaction.
  std::vector<Store::Delete> deletes;
  for (uint32_t i = 0; i < 200; i += 2) deletes.push_back({Database::tiles, tile_key(1, i, i)});
  ASSERT_TRUE(store->write({}, deletes).ok());

  const auto target = dir.path() / "compact";
  Status copied = store->compact_copy(target);
  ASSERT_TRUE(copied.ok()) << copied.error().message;
  EXPECT_LT(std::filesystem::file_size(target / "data.mdb"),
            std::filesystem::file_size(dir.path() / "src" / "data.mdb"));
  // A second copy to the same place is refused rather than clobbering.
  EXPECT_EQ(store->compact_copy(target).error().code, ErrorCode::invalid_input);

  Store::Options ro;
  auto copy = open_or_die(target, ro);
  ASSERT_TRUE(copy);
  for (Database db : {Database::meta, Database::tiles, Database::top, Database::progress, Database::tileinfo}) {
    std::vector<std::pair<Bytes, Bytes>> a, b;
    auto collect = [](auto& out) {
      return [&out](auto key, auto value) {
        out.emplace_back(Bytes(key.begin(), key.end()), Bytes(value.begin(), value.end()));
        return true;
      };
    };
    ASSERT_TRUE(store->for_each(db, {}, collect(a)).ok());
    ASSERT_TRUE(copy->for_each(db, {}, collect(b)).ok());
    EXPECT_EQ(a, b) << database_name(db);
  }
  EXPECT_EQ(*copy->entry_count(Database::tiles), 100u);
}

// The concurrency tests' data: value i of writer `level` (sizes vary, so pages fill unevenly),
// written one transaction each.
Bytes numbered_value(uint8_t level, uint32_t i) { return value_for(level * 100000u + i, 2000 + i); }
int write_numbered(Store& store, uint8_t level, uint32_t count) {  // returns the failed writes
  int failures = 0;
  for (uint32_t i = 0; i < count; ++i) {
    std::vector<Store::Put> puts = {{Database::tiles, tile_key(level, i, 0), numbered_value(level, i)}};
    if (!store.write(puts).ok()) ++failures;
  }
  return failures;
}
void expect_numbered(const Store& store, uint8_t level, uint32_t count) {
  for (uint32_t i = 0; i < count; ++i)
    EXPECT_EQ(get_or_die(store, Database::tiles, tile_key(level, i, 0)), numbered_value(level, i));
}

// The concurrency tests' store: a small first map, so the writes grow it while the other threads
// run, and no sync per commit.
Store::Options growing_options(uint64_t initial_map_size) {
  Store::Options options = rw_options();
  options.initial_map_size = initial_map_size;
  options.no_sync = true;
  return options;
}

TEST(LmdbStore, ConcurrentWritersAndReaders) {
  TempDir dir;
  const Store::Options options = growing_options(256 << 10);  // growth while readers run
  auto store = open_or_die(dir.path(), options);
  ASSERT_TRUE(store);
  constexpr uint32_t kPerWriter = 300;
  std::atomic<bool> writers_done{false};
  std::atomic<int> failures{0};

  auto writer = [&](uint8_t level) { failures += write_numbered(*store, level, kPerWriter); };
  auto reader = [&](uint64_t seed) {
    std::mt19937_64 rng(seed);
    while (!writers_done.load()) {
      const uint8_t level = static_cast<uint8_t>(1 + rng() % 2);
      const uint32_t i = static_cast<uint32_t>(rng() % kPerWriter);
      auto value = store->get(Database::tiles, tile_key(level, i, 0));
      if (!value.ok()) { ++failures; continue; }
      // A value, when present, is never torn.
      if (*value && **value != numbered_value(level, i)) ++failures;
      auto snapshot = store->snapshot();
      if (!snapshot.ok()) { ++failures; continue; }
      size_t count = 0;
      if (!snapshot->for_each(Database::tiles, tile_key_prefix(Method::mh, level),
                              [&](auto, auto) { return ++count, true; }).ok()) {
        ++failures;
      }
    }
  };
  std::thread r1(reader, 1), r2(reader, 2);
  std::thread w1(writer, 1), w2(writer, 2);
  w1.join();
  w2.join();
  writers_done = true;
  r1.join();
  r2.join();
  EXPECT_EQ(failures.load(), 0);
  EXPECT_GT(store->map_size(), options.initial_map_size);
  for (uint8_t level : {1, 2}) expect_numbered(*store, level, kPerWriter);
}

// The build flushes committed tiles from one thread while its workers write (builder/tile_pipeline.cpp):
// sync() from another thread, while writes grow the map (a remap), loses and breaks nothing.
TEST(LmdbStore, SyncWhileWritersGrowTheMap) {
  TempDir dir;
  auto store = open_or_die(dir.path(), growing_options(64 << 10));  // many growths during the writes
  ASSERT_TRUE(store);
  constexpr uint32_t kPerWriter = 800;
  std::atomic<bool> writers_done{false};
  std::atomic<int> failures{0};
  std::atomic<uint64_t> syncs{0};
  auto writer = [&](uint8_t level) { failures += write_numbered(*store, level, kPerWriter); };
  std::thread syncer([&] {
    while (!writers_done.load()) {
      if (!store->sync().ok()) ++failures;
      ++syncs;
    }
  });
  std::thread w1(writer, 1), w2(writer, 2);
  w1.join();
  w2.join();
  writers_done = true;
  syncer.join();
  EXPECT_EQ(failures.load(), 0);
  EXPECT_GT(syncs.load(), 0u);
  EXPECT_GE(store->map_size(), uint64_t{4} << 20);
  for (uint8_t level : {1, 2}) expect_numbered(*store, level, kPerWriter);
}

// Another process grows the map while this one has the store open read-only: the reader must adopt
// the new size (MDB_MAP_RESIZED) instead of failing.
TEST(LmdbStore, ReaderFollowsMapGrownByAnotherProcess) {
  TempDir dir;
  Store::Options options = rw_options();
  options.initial_map_size = 64 << 10;
  {
    auto store = open_or_die(dir.path(), options);
    ASSERT_TRUE(store);
    std::vector<Store::Put> first = {{Database::meta, bytes_of("k"), bytes_of("v")}};
    ASSERT_TRUE(store->write(first).ok());
  }
  Store::Options ro;
  auto reader = open_or_die(dir.path(), ro);
  ASSERT_TRUE(reader);
  const uint64_t before = reader->map_size();

  const pid_t child = fork();
  ASSERT_NE(child, -1);
  if (child == 0) {
    // Child: its own environment (never touch the parent's), grow the map, exit.
    auto opened = Store::open(dir.path(), options);
    if (!opened.ok()) _exit(2);
    std::vector<Store::Put> puts;
    for (uint32_t i = 0; i < 16; ++i) puts.push_back({Database::tiles, tile_key(0, i, 0), value_for(i, 256 << 10)});
    const bool ok = (*opened)->write(puts).ok();
    opened.value().reset();
    _exit(ok ? 0 : 3);
  }
  int wstatus = 0;
  ASSERT_EQ(waitpid(child, &wstatus, 0), child);
  ASSERT_TRUE(WIFEXITED(wstatus));
  ASSERT_EQ(WEXITSTATUS(wstatus), 0);

  for (uint32_t i = 0; i < 16; ++i) {
    auto value = reader->get(Database::tiles, tile_key(0, i, 0));
    ASSERT_TRUE(value.ok()) << value.error().message;
    ASSERT_TRUE(value->has_value()) << i;
    EXPECT_EQ(**value, value_for(i, 256 << 10));
  }
  EXPECT_GT(reader->map_size(), before);
}

}  // namespace
}  // namespace shadowtiles::store
