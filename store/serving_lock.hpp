// ServingLock: keeps a builder from rewriting a store that a server is answering from (docs/architecture.md §9:
// a new build goes into a new directory, and the server swaps to it). A server holds a shared lock
// on `<store>/serving.lock` for as long as it serves the store; a build takes the exclusive lock for
// as long as it writes. Either side fails fast (no waiting) when the other holds it. flock(2) locks
// belong to the open file, so they vanish with a crashed process: nothing stale to clean up.
// Not for NFS (neither is LMDB).
// Errors: invalid_input when the other side holds the lock (message says which), io_error when the
// lock file cannot be created or opened.
// Thread safety: one object per holder; movable, not copyable.
#pragma once

#include <filesystem>

#include "common/result.hpp"

namespace shadowtiles::store {

class ServingLock {
 public:
  enum class Kind { serve, build };
  // FORMAT: the lock file's name inside a store directory.
  static constexpr const char* kFileName = "serving.lock";

  static Result<ServingLock> acquire(const std::filesystem::path& store_dir, Kind kind);
  ServingLock(ServingLock&& other) noexcept : fd_(other.fd_) { other.fd_ = -1; }
  ServingLock& operator=(ServingLock&& other) noexcept;
  ServingLock(const ServingLock&) = delete;
  ServingLock& operator=(const ServingLock&) = delete;
  ~ServingLock();

 private:
  explicit ServingLock(int fd) : fd_(fd) {}
  int fd_ = -1;
};

}  // namespace shadowtiles::store
