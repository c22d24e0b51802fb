#include "client/http_tile_source.hpp"

#include <algorithm>
#include <thread>

#include <httplib.h>
#include <nlohmann/json.hpp>

#include "codec/store_meta.hpp"
#include "store/blob.hpp"

namespace shadowtiles {
namespace {

// Bodies above this are refused while they stream in: no stored blob comes near it (tiles are
// compressed; kMaxBlobRawSize bounds the raw side), and a hostile server must not exhaust memory.
constexpr size_t kMaxBodyBytes = size_t(1) << 30;

bool retryable_status(int status) { return status == 502 || status == 503 || status == 504; }

// The server's JSON error ({"error": message, "code": code}) or the start of whatever it sent.
std::pair<std::string, std::string> server_error(const std::string& body) {
  try {
    auto json = nlohmann::json::parse(body);
    std::string code = json.contains("code") && json["code"].is_string() ? json["code"].get<std::string>() : "";
    std::string message = json.contains("error") && json["error"].is_string() ? json["error"].get<std::string>() : "";
    return {code, message};
  } catch (const nlohmann::json::exception&) {
    return {"", body.substr(0, 200)};
  }
}

std::string etag_of(const std::vector<uint8_t>& checked_blob) {
  auto header = store::check_blob(checked_blob);
  if (!header) return "";
  std::string tag(1, '"');  // appended, not "\"" + ...: GCC 12 warns falsely (-Wrestrict) on that
  tag += store::checksum_hex(header->checksum);
  tag += '"';
  return tag;
}

std::string strip_etag(std::string tag) {
  if (tag.starts_with("W/")) tag.erase(0, 2);
  if (tag.size() >= 2 && tag.front() == '"' && tag.back() == '"') tag = tag.substr(1, tag.size() - 2);
  return tag;
}

}  // namespace

HttpTileSource::HttpTileSource(std::string base_url, std::string path_prefix, Options options)
    : base_url_(std::move(base_url)), path_prefix_(std::move(path_prefix)), options_(std::move(options)) {}

HttpTileSource::~HttpTileSource() = default;

Result<std::shared_ptr<HttpTileSource>> HttpTileSource::open(const std::string& url, const Options& options) {
  if (options.max_attempts == 0) return make_error(ErrorCode::invalid_input, "max_attempts must be >= 1");
  const size_t scheme_end = url.find("://");
  if (scheme_end == std::string::npos || (url.substr(0, scheme_end) != "http" && url.substr(0, scheme_end) != "https"))
    return make_error(ErrorCode::invalid_input, "server URL must start with http:// or https://: '" + url + "'");
  const size_t host_begin = scheme_end + 3;
  const size_t path_begin = url.find('/', host_begin);
  std::string base = url.substr(0, path_begin);
  std::string prefix = path_begin == std::string::npos ? "" : url.substr(path_begin);
  while (!prefix.empty() && prefix.back() == '/') prefix.pop_back();
  if (base.size() == host_begin || prefix.find_first_of("?# ") != std::string::npos)
    return make_error(ErrorCode::invalid_input, "malformed server URL '" + url + "'");
  {
    httplib::Client probe(base);
    if (!probe.is_valid()) return make_error(ErrorCode::invalid_input, "malformed server URL '" + url + "'");
  }
  auto source = std::shared_ptr<HttpTileSource>(new HttpTileSource(base, prefix, options));

  auto build = source->get("/v1/build");
  if (!build) return build.error();
  if (build->status != 200) {
    auto [code, message] = server_error(build->body);
    return make_error(build->status == 404 ? ErrorCode::not_found : ErrorCode::io_error,
                      "GET " + source->describe() + "/v1/build: HTTP " + std::to_string(build->status) + " " + message);
  }
  auto meta = StoreMeta::parse(build->body);
  if (!meta) return make_error(meta.error().code, source->describe() + ": " + meta.error().message);
  source->meta_text_ = std::move(build->body);
  // The build id names immutable URLs and the disk cache's directory; meta's config_hash is it (the
  // ETag of /v1/build carries the same).
  source->build_id_ = meta->config_hash.empty() ? strip_etag(build->etag) : meta->config_hash;

  auto layout = meta->layout();
  if (options.use_build_routes && layout && !meta->methods.empty() && !source->build_id_.empty()) {
    // Does the server have /v1/builds/{id}/...? Ask for one tile's headers only.
    store::TileKey probe_key{meta->methods.front(), layout->tile_level(), 0, 0};
    source->build_routes_ = true;
    std::string path = source->path_prefix_ + source->tile_path(probe_key);
    source->build_routes_ = false;
    auto client = source->acquire_client();
    ++source->requests_;
    auto head = client->Head(path);
    if (head && (head->status == 200 || head->status == 204)) source->build_routes_ = true;
    source->release_client(std::move(client));
  }

  if (!options.disk_cache_dir.empty()) {
    if (!DiskTileCache::safe_component(source->build_id_))
      return make_error(ErrorCode::corrupt_data,
                        "build id '" + source->build_id_.substr(0, 64) + "' cannot name a cache directory");
    auto cache = DiskTileCache::open(options.disk_cache_dir, options.disk_cache_bytes);
    if (!cache) return cache.error();
    source->disk_cache_ = std::move(*cache);
  }
  return source;
}

std::unique_ptr<httplib::Client> HttpTileSource::acquire_client() const {
  {
    std::lock_guard lock(pool_mutex_);
    if (!idle_clients_.empty()) {
      auto client = std::move(idle_clients_.back());
      idle_clients_.pop_back();
      return client;
    }
  }
  auto client = std::make_unique<httplib::Client>(base_url_);
  client->set_keep_alive(true);
  client->set_tcp_nodelay(true);
  client->set_connection_timeout(options_.connect_timeout);
  client->set_read_timeout(options_.read_timeout);
  return client;
}

void HttpTileSource::release_client(std::unique_ptr<httplib::Client> client) const {
  std::lock_guard lock(pool_mutex_);
  idle_clients_.push_back(std::move(client));
}

Result<HttpTileSource::Response> HttpTileSource::get(const std::string& path, const std::string& if_none_match) const {
  const std::string full_path = path_prefix_ + path;
  httplib::Headers headers;
  if (!if_none_match.empty()) headers.emplace("If-None-Match", if_none_match);
  std::chrono::milliseconds backoff = options_.initial_backoff;
  std::string last_cause;
  for (unsigned attempt = 0; attempt < options_.max_attempts; ++attempt) {
    if (attempt > 0) {
      ++retries_;
      std::this_thread::sleep_for(backoff);
      backoff = std::min(backoff * 2, options_.max_backoff);
    }
    auto client = acquire_client();
    ++requests_;
    Response response;
    bool too_large = false;
    auto result = client->Get(
        full_path, headers,
        [&](const httplib::Response& head) {
          response.status = head.status;
          response.etag = head.get_header_value("ETag");
          response.content_type = head.get_header_value("Content-Type");
          return true;
        },
        [&](const char* data, size_t length) {
          if (response.body.size() + length > kMaxBodyBytes) {
            too_large = true;
            return false;
          }
          response.body.append(data, length);
          return true;
        });
    if (too_large)
      return make_error(ErrorCode::corrupt_data,
                        "GET " + base_url_ + full_path + ": answer larger than " + std::to_string(kMaxBodyBytes) + " bytes");
    if (!result) {
      // The connection is in an unknown state: drop it rather than return it to the pool.
      last_cause = httplib::to_string(result.error());
      continue;
    }
    response.status = result->status;  // also for 204/304, which have no body callback
    if (response.etag.empty()) response.etag = result->get_header_value("ETag");
    release_client(std::move(client));
    if (retryable_status(response.status)) {
      last_cause = "HTTP " + std::to_string(response.status) + " " + server_error(response.body).second;
      continue;
    }
    return response;
  }
  return make_error(ErrorCode::io_error, "GET " + base_url_ + full_path + " failed after " +
                                             std::to_string(options_.max_attempts) + " attempt(s): " + last_cause);
}

std::string HttpTileSource::tile_path(const store::TileKey& key) const {
  std::string tail = std::string("tiles/") + store::method_name(key.method) + "/" + std::to_string(key.level) + "/" +
                     std::to_string(key.x) + "/" + std::to_string(key.y);
  return build_routes_ ? "/v1/builds/" + build_id_ + "/" + tail : "/v1/" + tail;
}

Result<std::optional<std::vector<uint8_t>>> HttpTileSource::fetch_blob(const std::string& path, store::Method method,
                                                                       const std::string& cache_name,
                                                                       bool is_tile) const {
  const std::string url = base_url_ + path_prefix_ + path;
  std::optional<DiskTileCache::Entry> cached;
  if (disk_cache_) cached = disk_cache_->get(build_id_, cache_name);
  if (cached && cached->empty) {  // an empty tile of this build stays empty
    ++disk_hits_;
    return std::optional<std::vector<uint8_t>>{};
  }
  if (cached) {
    auto header = store::check_blob(cached->blob);  // the cache checked it; the method is ours to check
    if (!header || header->method != method) {
      disk_cache_->remove(build_id_, cache_name);
      cached.reset();
    } else if (!options_.revalidate) {
      ++disk_hits_;
      return std::optional<std::vector<uint8_t>>(std::move(cached->blob));
    }
  }
  const std::string etag = cached ? etag_of(cached->blob) : "";
  for (int attempt = 0; attempt < 2; ++attempt) {
    auto response = get(path, attempt == 0 ? etag : "");
    if (!response) {
      if (cached) {  // offline: the cached blob is verified and of the same build
        ++disk_hits_;
        return std::optional<std::vector<uint8_t>>(std::move(cached->blob));
      }
      return response.error();
    }
    const int status = response->status;
    if (status == 304 && cached) {
      ++not_modified_;
      ++disk_hits_;
      return std::optional<std::vector<uint8_t>>(std::move(cached->blob));
    }
    if (status == 200) {
      bytes_received_ += response->body.size();
      if (is_tile) ++tiles_fetched_;
      std::vector<uint8_t> blob(response->body.begin(), response->body.end());
      auto header = store::check_blob(blob);
      if (header && header->method != method)
        header = make_error(ErrorCode::corrupt_data, "the blob holds another method than its URL");
      if (header) {
        if (disk_cache_) disk_cache_->put(build_id_, cache_name, {false, blob});
        return std::optional<std::vector<uint8_t>>(std::move(blob));
      }
      if (attempt == 0) {
        ++corrupt_refetches_;
        continue;
      }
      return make_error(ErrorCode::corrupt_data, "GET " + url + ": the blob fails its checks twice, not used: " +
                                                     header.error().message);
    }
    if (status == 204) {
      if (is_tile) ++tiles_fetched_;
      if (disk_cache_ && is_tile) disk_cache_->put(build_id_, cache_name, {true, {}});
      return std::optional<std::vector<uint8_t>>{};
    }
    if (cached) disk_cache_->remove(build_id_, cache_name);  // the server no longer has it as cached
    auto [code, message] = server_error(response->body);
    if (status == 404 && !is_tile) return std::optional<std::vector<uint8_t>>{};  // the method has no top tree
    if (status == 404 && build_routes_)
      return make_error(ErrorCode::not_found, "GET " + url + ": HTTP 404: the server no longer serves build " +
                                                  build_id_ + " (" + message + ")");
    if (status == 404) return make_error(ErrorCode::not_found, "GET " + url + ": HTTP 404 " + message);
    if (code == "corrupt_data")
      return make_error(ErrorCode::corrupt_data, "GET " + url + ": the server's stored blob fails its checks (" +
                                                     message + ")");
    return make_error(status >= 400 && status < 500 ? ErrorCode::invalid_input : ErrorCode::io_error,
                      "GET " + url + ": unexpected HTTP " + std::to_string(status) + " " + message);
  }
  return make_error(ErrorCode::corrupt_data, "GET " + url + ": the blob fails its checks");  // not reached
}

Result<std::string> HttpTileSource::meta_text() const { return meta_text_; }

Result<std::optional<std::vector<uint8_t>>> HttpTileSource::tile_blob(const store::TileKey& key) const {
  std::string name = std::string("tile-") + store::method_name(key.method) + "-" + std::to_string(key.level) + "-" +
                     std::to_string(key.x) + "-" + std::to_string(key.y);
  return fetch_blob(tile_path(key), key.method, name, true);
}

Result<std::optional<std::vector<uint8_t>>> HttpTileSource::top_blob(store::Method method) const {
  const std::string route = build_routes_ ? "/v1/builds/" + build_id_ + "/skiplist" : std::string("/v1/skiplist");
  return fetch_blob(route + "?method=" + store::method_name(method), method,
                    std::string("top-") + store::method_name(method), false);
}

std::string HttpTileSource::describe() const { return base_url_ + path_prefix_; }

HttpFetchStats HttpTileSource::stats() const {
  HttpFetchStats stats;
  stats.requests = requests_;
  stats.retries = retries_;
  stats.tiles_fetched = tiles_fetched_;
  stats.bytes_received = bytes_received_;
  stats.not_modified = not_modified_;
  stats.disk_hits = disk_hits_;
  stats.corrupt_refetches = corrupt_refetches_;
  return stats;
}

}  // namespace shadowtiles
