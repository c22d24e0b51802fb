// VerifiedBlobs: the stored blobs (tiles, skip lists) of the served build whose checks passed
// lately, so a hot blob's checksum is not recomputed on every GET. XXH64 over a raw tile's ~400 kB
// was 18 % of the server's CPU under 64 keep-alive tile GETs (docs/architecture.md §10).
// An entry answers only for the same build (the served ShadowMap, compared by owner), the same
// database and key, the same bytes' address and size in the store's map, and for `recheck_after`
// after its check. The served store is not written while it is served (store::ServingLock), so
// within one map a key's bytes stay where they are; bytes that change under the map anyway (a page
// read again from a failing disk, a hand edit) fail their next check, at most `recheck_after`
// later. A corrupt blob is never remembered. recheck_after = 0 checks on every GET.
// Thread safety: all members may be called concurrently (one mutex; a lookup is a hash probe).
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <unordered_map>

#include "store/blob.hpp"
#include "store/lmdb_store.hpp"

namespace shadowtiles::server {

class VerifiedBlobs {
 public:
  using Clock = std::chrono::steady_clock;
  VerifiedBlobs(std::chrono::milliseconds recheck_after, size_t max_entries);

  // The header stored with `bytes` when its check still stands; nullopt means: check it.
  std::optional<store::BlobHeader> recall(const std::shared_ptr<const void>& build, store::Database db,
                                          std::span<const uint8_t> key, std::span<const uint8_t> bytes) const;
  // Records a passed check of `bytes`. A new build forgets the previous build's entries; a full
  // table starts over (a cold entry costs one check).
  void remember(const std::shared_ptr<const void>& build, store::Database db, std::span<const uint8_t> key,
                std::span<const uint8_t> bytes, const store::BlobHeader& header);

  size_t size() const;

 private:
  struct Entry {
    const uint8_t* data;
    size_t size;
    store::BlobHeader header;
    Clock::time_point checked;
  };
  static std::string entry_key(store::Database db, std::span<const uint8_t> key);
  bool same_build(const std::shared_ptr<const void>& build) const;

  const std::chrono::milliseconds recheck_after_;
  const size_t max_entries_;
  mutable std::mutex mutex_;
  std::weak_ptr<const void> build_;  // owner identity: a freed build's address may be reused
  std::unordered_map<std::string, Entry> entries_;
};

}  // namespace shadowtiles::server
