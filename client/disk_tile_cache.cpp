#include "client/disk_tile_cache.hpp"

#include <algorithm>
#include <atomic>
#include <fstream>
#include <system_error>
#include <unistd.h>

#include "store/blob.hpp"

namespace shadowtiles {
namespace {

namespace fs = std::filesystem;

// An empty-tile marker holds no bytes but costs a directory entry: count it so the bound also
// bounds the number of files.
constexpr uint64_t kMarkerCost = 64;

uint64_t cost_of(uint64_t file_bytes) { return std::max(file_bytes, kMarkerCost); }

std::optional<std::vector<uint8_t>> read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) return std::nullopt;
  return bytes;
}

// Unique per process and call, so concurrent writers never share a temporary file.
fs::path temporary_beside(const fs::path& path) {
  static std::atomic<uint64_t> counter{0};
  return path.string() + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
}

}  // namespace

Result<std::unique_ptr<DiskTileCache>> DiskTileCache::open(const fs::path& dir, uint64_t max_bytes) {
  if (max_bytes == 0) return make_error(ErrorCode::invalid_input, "disk cache budget must be > 0 bytes");
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return make_error(ErrorCode::io_error, "disk cache " + dir.string() + ": " + ec.message());
  auto cache = std::unique_ptr<DiskTileCache>(new DiskTileCache(dir, max_bytes));
  // Existing entries, oldest first, so eviction removes what earlier runs used least recently.
  std::vector<std::pair<fs::file_time_type, std::pair<fs::path, uint64_t>>> found;
  for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::recursive_directory_iterator();
       it.increment(ec)) {
    if (!it->is_regular_file(ec)) continue;
    const fs::path& path = it->path();
    if (path.string().find(".tmp.") != std::string::npos) continue;  // another writer's, or a crash's
    auto ext = path.extension();
    if (ext != ".blob" && ext != ".empty") continue;
    found.push_back({it->last_write_time(ec), {path, it->file_size(ec)}});
  }
  if (ec) return make_error(ErrorCode::io_error, "disk cache " + dir.string() + ": " + ec.message());
  std::sort(found.begin(), found.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (auto& [time, file] : found) {
    cache->files_[file.first] = FileInfo{cost_of(file.second), ++cache->tick_};
    cache->total_bytes_ += cost_of(file.second);
  }
  std::lock_guard lock(cache->mutex_);
  cache->evict_locked();
  return cache;
}

bool DiskTileCache::safe_component(const std::string& text) {
  if (text.empty() || text.size() > 128 || text == "." || text == "..") return false;
  return std::all_of(text.begin(), text.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-' ||
           c == '.';
  });
}

fs::path DiskTileCache::entry_path(const std::string& build_id, const std::string& name, bool empty) const {
  return dir_ / build_id / (name + (empty ? ".empty" : ".blob"));
}

std::optional<DiskTileCache::Entry> DiskTileCache::get(const std::string& build_id, const std::string& name) {
  if (!safe_component(build_id) || !safe_component(name)) return std::nullopt;
  std::error_code ec;
  const fs::path marker = entry_path(build_id, name, true);
  if (fs::exists(marker, ec)) {
    std::lock_guard lock(mutex_);
    if (auto it = files_.find(marker); it != files_.end()) it->second.last_use = ++tick_;
    return Entry{true, {}};
  }
  const fs::path path = entry_path(build_id, name, false);
  auto bytes = read_file(path);
  if (!bytes) return std::nullopt;
  if (!store::check_blob(*bytes)) {
    remove(build_id, name);  // damaged on disk: refetch rather than trust it
    return std::nullopt;
  }
  std::lock_guard lock(mutex_);
  auto& info = files_[path];
  if (info.bytes == 0) {  // written by another process since open
    info.bytes = cost_of(bytes->size());
    total_bytes_ += info.bytes;
  }
  info.last_use = ++tick_;
  return Entry{false, std::move(*bytes)};
}

void DiskTileCache::put(const std::string& build_id, const std::string& name, const Entry& entry) {
  if (!safe_component(build_id) || !safe_component(name)) return;
  const fs::path path = entry_path(build_id, name, entry.empty);
  std::error_code ec;
  fs::create_directories(path.parent_path(), ec);
  if (ec) return;
  const fs::path temporary = temporary_beside(path);
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) return;
    out.write(reinterpret_cast<const char*>(entry.blob.data()), std::streamsize(entry.blob.size()));
    if (!out) {
      out.close();
      fs::remove(temporary, ec);
      return;
    }
  }
  fs::rename(temporary, path, ec);
  if (ec) {
    fs::remove(temporary, ec);
    return;
  }
  std::lock_guard lock(mutex_);
  forget_locked(path);
  files_[path] = FileInfo{cost_of(entry.blob.size()), ++tick_};
  total_bytes_ += cost_of(entry.blob.size());
  evict_locked();
}

void DiskTileCache::remove(const std::string& build_id, const std::string& name) {
  if (!safe_component(build_id) || !safe_component(name)) return;
  std::lock_guard lock(mutex_);
  for (bool empty : {false, true}) {
    const fs::path path = entry_path(build_id, name, empty);
    std::error_code ec;
    fs::remove(path, ec);
    forget_locked(path);
  }
}

uint64_t DiskTileCache::bytes() const {
  std::lock_guard lock(mutex_);
  return total_bytes_;
}

void DiskTileCache::forget_locked(const fs::path& path) {
  if (auto it = files_.find(path); it != files_.end()) {
    total_bytes_ -= it->second.bytes;
    files_.erase(it);
  }
}

void DiskTileCache::evict_locked() {
  while (total_bytes_ > max_bytes_ && !files_.empty()) {
    auto victim = std::min_element(files_.begin(), files_.end(),
                                   [](const auto& a, const auto& b) { return a.second.last_use < b.second.last_use; });
    std::error_code ec;
    fs::remove(victim->first, ec);
    total_bytes_ -= victim->second.bytes;
    files_.erase(victim);
  }
}

}  // namespace shadowtiles
