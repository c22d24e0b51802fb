#include "server/verified_blobs.hpp"

namespace shadowtiles::server {

VerifiedBlobs::VerifiedBlobs(std::chrono::milliseconds recheck_after, size_t max_entries)
    : recheck_after_(recheck_after), max_entries_(max_entries) {}

std::string VerifiedBlobs::entry_key(store::Database db, std::span<const uint8_t> key) {
  std::string k(1, char(db));  // tile keys fit the small-string buffer: no allocation
  k.append(reinterpret_cast<const char*>(key.data()), key.size());
  return k;
}

bool VerifiedBlobs::same_build(const std::shared_ptr<const void>& build) const {
  return !build_.owner_before(build) && !build.owner_before(build_) && !build_.expired();
}

std::optional<store::BlobHeader> VerifiedBlobs::recall(const std::shared_ptr<const void>& build,
                                                       store::Database db, std::span<const uint8_t> key,
                                                       std::span<const uint8_t> bytes) const {
  if (recheck_after_.count() == 0 || !build) return std::nullopt;
  const std::string k = entry_key(db, key);
  const Clock::time_point now = Clock::now();
  std::lock_guard lock(mutex_);
  if (!same_build(build)) return std::nullopt;
  auto it = entries_.find(k);
  if (it == entries_.end()) return std::nullopt;
  const Entry& e = it->second;
  if (e.data != bytes.data() || e.size != bytes.size() || now - e.checked >= recheck_after_) return std::nullopt;
  return e.header;
}

void VerifiedBlobs::remember(const std::shared_ptr<const void>& build, store::Database db,
                             std::span<const uint8_t> key, std::span<const uint8_t> bytes,
                             const store::BlobHeader& header) {
  if (recheck_after_.count() == 0 || !build || max_entries_ == 0) return;
  std::string k = entry_key(db, key);
  const Clock::time_point now = Clock::now();
  std::lock_guard lock(mutex_);
  if (!same_build(build)) {
    entries_.clear();
    build_ = build;
  }
  if (entries_.size() >= max_entries_ && !entries_.count(k)) entries_.clear();
  entries_.insert_or_assign(std::move(k), Entry{bytes.data(), bytes.size(), header, now});
}

size_t VerifiedBlobs::size() const {
  std::lock_guard lock(mutex_);
  return entries_.size();
}

}  // namespace shadowtiles::server
