// DiskTileCache: blobs fetched from a server, kept on local disk between runs (docs/architecture.md §10: tile
// URLs are immutable per build), bounded in bytes with least-recently-used eviction.
// Layout: <dir>/<build id>/<name>.blob holds a blob exactly as served (its ETag is its own checksum,
// so nothing else is stored); <name>.empty marks a tile the server answered 204 (empty) for.
// Entries are keyed by build id, so a server switching builds never mixes tiles of two builds.
// Reads verify the blob (store::check_blob); a file failing its checks is deleted and reported
// absent, so a damaged cache costs a refetch, never a wrong answer. Writes go to a temporary file
// renamed into place, so a crash or a concurrent process never leaves a half-written entry.
// Errors: open → io_error when the directory cannot be created or listed, invalid_input for a zero
// budget. get/put never fail: disk trouble is logged and the cache behaves as a miss.
// Thread safety: all members may be called concurrently. Several processes may share a directory
// (each keeps its own byte count, so the bound is per process).
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "common/result.hpp"

namespace shadowtiles {

class DiskTileCache {
 public:
  // One cached answer: a blob, or "the server has no blob here" (an empty tile).
  struct Entry {
    bool empty = false;
    std::vector<uint8_t> blob;
  };

  static Result<std::unique_ptr<DiskTileCache>> open(const std::filesystem::path& dir, uint64_t max_bytes);

  // Build ids and names become path components: only [A-Za-z0-9_.-], 1..128 characters, not "."
  // or "..". Anything else (the build id comes from the server) is never cached.
  static bool safe_component(const std::string& text);

  std::optional<Entry> get(const std::string& build_id, const std::string& name);
  void put(const std::string& build_id, const std::string& name, const Entry& entry);
  void remove(const std::string& build_id, const std::string& name);

  uint64_t bytes() const;
  uint64_t max_bytes() const { return max_bytes_; }
  const std::filesystem::path& dir() const { return dir_; }

 private:
  DiskTileCache(std::filesystem::path dir, uint64_t max_bytes) : dir_(std::move(dir)), max_bytes_(max_bytes) {}
  std::filesystem::path entry_path(const std::string& build_id, const std::string& name, bool empty) const;
  void forget_locked(const std::filesystem::path& path);
  void evict_locked();

  struct FileInfo {
    uint64_t bytes = 0;
    uint64_t last_use = 0;  // tick of the last get/put; files found at open are ordered by mtime
  };
  std::filesystem::path dir_;
  uint64_t max_bytes_;
  mutable std::mutex mutex_;
  std::map<std::filesystem::path, FileInfo> files_;
  uint64_t total_bytes_ = 0;
  uint64_t tick_ = 0;
};

}  // namespace shadowtiles
