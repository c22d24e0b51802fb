// `shadowtiles merge SHARD... --out STORE` (docs/scale-out.md): joins the shard stores of one
// sharded build (`build --shard I/N`) into the store a one-machine build of the same config writes:
// every tile blob byte-identical, the same tile info and progress records, top levels and skip list
// computed from the tiles' info records (no tile is decoded), the meta marked complete.
//
// Checks before anything is written, each error naming the shard store: not a shard store, a share
// not finished, a different build (config hash, shard count), the same share twice, a missing share,
// shares whose Morton ranges do not tile the map, a share whose progress records do not match its
// range, tiles without info records. While copying: a key outside its shard's range or present in
// two shards (overlap), a blob failing its checks (corrupt_data).
//
// Streaming: per database, a k-way merge of the shards' key-ordered chunks (short read
// transactions; each copied value's pages are dropped from the process at once, and the kernel is
// asked to fetch the next chunk of each shard while this one is merged), written with MDB_APPEND in
// transactions of at most `transaction_bytes`. Memory: shards × 2 × chunk_bytes + transaction_bytes
// and the transaction's pages, whatever the store's size. Resumable: a killed merge restarts, with the same shards, after the
// last key each database holds. Errors: invalid_input (the checks; exit 2), corrupt_data (exit 4),
// io_error / out_of_space (exit 1).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/result.hpp"

namespace shadowtiles {

struct MergeConfig {
  std::vector<std::filesystem::path> shards;
  std::filesystem::path out;
  uint64_t transaction_bytes = 64ull << 20;
  uint64_t chunk_bytes = 8ull << 20;  // read ahead per shard
  uint64_t initial_map_size = 1ull << 30;
  bool overwrite = false;
  std::function<void(const std::string& line)> on_progress;
  uint64_t debug_kill_after_transactions = 0;  // test hook: SIGKILL self after N committed transactions
};

struct MergeSummary {
  nlohmann::json stats;
};

Result<MergeSummary> run_merge(const MergeConfig& config);

}  // namespace shadowtiles
