#include "server/server_config.hpp"

#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <sstream>

#include "client/shadow_map.hpp"
#include "codec/json_integer.hpp"

namespace shadowtiles::server {
namespace {

Error bad(const std::string& key, const std::string& why) {
  return make_error(ErrorCode::invalid_input, "config key '" + key + "': " + why);
}

// Unsigned integer in [lo, hi]; JSON floats such as 2.0 are refused so types stay exact.
template <class T>
Status read_uint(const nlohmann::json& value, const std::string& key, uint64_t lo, uint64_t hi, T& out) {
  if (!value.is_number_integer()) return bad(key, "expected an integer");
  const std::optional<uint64_t> v = json_integer_in<uint64_t>(value, lo, hi);
  if (!v) return bad(key, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  out = T(*v);
  return {};
}

}  // namespace

Status ServerConfig::validate() const {
  if (host.empty()) return bad("host", "must not be empty");
  if (port < 0 || port > 65535) return bad("port", "must be in [0, 65535]");
  if (threads < 1 || threads > 256) return bad("threads", "must be in [1, 256]");
  if (cache_bytes < (uint64_t(1) << 20)) return bad("cache_bytes", "must be at least 1 MiB");
  if (max_body_bytes < 12) return bad("max_body_bytes", "must be at least 12 (one binary point)");
  if (max_batch_points < 1) return bad("max_batch_points", "must be at least 1");
  if (max_pcf < 1 || max_pcf > ShadowMap::kMaxPcfKernel || max_pcf % 2 == 0)
    return bad("max_pcf", "must be odd and in [1, " + std::to_string(ShadowMap::kMaxPcfKernel) + "]");
  for (const std::string& origin : cors_origins)
    if (origin.empty() || origin == "*" || origin.find_first_of(" \t\r\n,") != std::string::npos)
      return bad("cors_origins", "each entry must be one exact origin such as \"https://example.org\"");
  if (read_timeout_s < 1 || read_timeout_s > 3600) return bad("read_timeout_s", "must be in [1, 3600]");
  if (write_timeout_s < 1 || write_timeout_s > 3600) return bad("write_timeout_s", "must be in [1, 3600]");
  if (body_timeout_s < 1 || body_timeout_s > 3600) return bad("body_timeout_s", "must be in [1, 3600]");
  if (max_connections < threads) return bad("max_connections", "must be at least `threads`");
  if (max_connections > 4096) return bad("max_connections", "must be at most 4096 (one I/O thread each)");
  // LMDB has 126 reader slots per process; the query workers' tile reads need some of them.
  if (max_pinned_sends > 100) return bad("max_pinned_sends", "must be in [0, 100] (LMDB has 126 reader slots)");
  if (blob_recheck_ms > 3600000) return bad("blob_recheck_ms", "must be in [0, 3600000] (0: check every GET)");
  if (max_batch_cost < 1) return bad("max_batch_cost", "must be at least 1");
  if (query_wait_ms < 1 || query_wait_ms > 600000) return bad("query_wait_ms", "must be in [1, 600000]");
  if (keep_alive_max_count < 1) return bad("keep_alive_max_count", "must be at least 1");
  if (keep_alive_timeout_s < 1 || keep_alive_timeout_s > 3600)
    return bad("keep_alive_timeout_s", "must be in [1, 3600]");
  if (reload_poll_s > 86400) return bad("reload_poll_s", "must be in [0, 86400] (0: reload on SIGHUP only)");
  if (render_threads < 1 || render_threads > 64) return bad("render_threads", "must be in [1, 64]");
  if (render_queue < 1 || render_queue > 4096) return bad("render_queue", "must be in [1, 4096]");
  if (render_timeout_ms < 10 || render_timeout_ms > 600000) return bad("render_timeout_ms", "must be in [10, 600000]");
  if (render_cache_bytes < (uint64_t(1) << 20)) return bad("render_cache_bytes", "must be at least 1 MiB");
  return {};
}

nlohmann::json ServerConfig::to_json() const {
  return {{"store", store},
          {"host", host},
          {"port", port},
          {"threads", threads},
          {"cache_bytes", cache_bytes},
          {"max_body_bytes", max_body_bytes},
          {"max_batch_points", max_batch_points},
          {"max_pcf", max_pcf},
          {"cache_control_max_age", cache_control_max_age},
          {"cors_origins", cors_origins},
          {"read_timeout_s", read_timeout_s},
          {"body_timeout_s", body_timeout_s},
          {"write_timeout_s", write_timeout_s},
          {"max_connections", max_connections},
          {"max_connections_per_address", max_connections_per_address},
          {"max_pinned_sends", max_pinned_sends},
          {"blob_recheck_ms", blob_recheck_ms},
          {"max_batch_cost", max_batch_cost},
          {"query_wait_ms", query_wait_ms},
          {"keep_alive_max_count", keep_alive_max_count},
          {"keep_alive_timeout_s", keep_alive_timeout_s},
          {"reload_poll_s", reload_poll_s},
          {"render_threads", render_threads},
          {"render_queue", render_queue},
          {"render_timeout_ms", render_timeout_ms},
          {"render_cache_bytes", render_cache_bytes},
          {"leaflet_dir", leaflet_dir},
          {"replica_name", replica_name}};
}

Result<ServerConfig> ServerConfig::from_json(const nlohmann::json& json, ServerConfig config) {
  if (!json.is_object()) return make_error(ErrorCode::invalid_input, "config must be a JSON object");
  constexpr uint64_t kU32 = std::numeric_limits<uint32_t>::max();
  constexpr uint64_t kU64 = std::numeric_limits<uint64_t>::max();
  using Reader = std::function<Status(const nlohmann::json&, const std::string&)>;
  const std::map<std::string, Reader> readers = {
      {"store",
       [&](const nlohmann::json& v, const std::string& k) -> Status {
         if (!v.is_string()) return bad(k, "expected a string (the store directory)");
         config.store = v.get<std::string>();
         return {};
       }},
      {"host",
       [&](const nlohmann::json& v, const std::string& k) -> Status {
         if (!v.is_string()) return bad(k, "expected a string");
         config.host = v.get<std::string>();
         return {};
       }},
      {"port", [&](auto& v, auto& k) { return read_uint(v, k, 0, 65535, config.port); }},
      {"threads", [&](auto& v, auto& k) { return read_uint(v, k, 1, 256, config.threads); }},
      {"cache_bytes", [&](auto& v, auto& k) { return read_uint(v, k, 0, kU64, config.cache_bytes); }},
      {"max_body_bytes", [&](auto& v, auto& k) { return read_uint(v, k, 0, kU64, config.max_body_bytes); }},
      {"max_batch_points", [&](auto& v, auto& k) { return read_uint(v, k, 0, kU64, config.max_batch_points); }},
      {"max_pcf", [&](auto& v, auto& k) { return read_uint(v, k, 0, kU32, config.max_pcf); }},
      {"cache_control_max_age",
       [&](auto& v, auto& k) { return read_uint(v, k, 0, kU32, config.cache_control_max_age); }},
      {"cors_origins",
       [&](const nlohmann::json& v, const std::string& k) -> Status {
         if (!v.is_array()) return bad(k, "expected a list of origin strings");
         config.cors_origins.clear();
         for (const auto& item : v) {
           if (!item.is_string()) return bad(k, "expected a list of origin strings");
           config.cors_origins.push_back(item.get<std::string>());
         }
         return {};
       }},
      {"read_timeout_s", [&](auto& v, auto& k) { return read_uint(v, k, 0, kU32, config.read_timeout_s); }},
      {"write_timeout_s", [&](auto& v, auto& k) { return read_uint(v, k, 0, kU32, config.write_timeout_s); }},
      {"body_timeout_s", [&](auto& v, auto& k) { return read_uint(v, k, 0, kU32, config.body_timeout_s); }},
      {"max_connections", [&](auto& v, auto& k) { return read_uint(v, k, 0, kU32, config.max_connections); }},
      {"max_connections_per_address",
       [&](auto& v, auto& k) { return read_uint(v, k, 0, kU32, config.max_connections_per_address); }},
      {"max_pinned_sends", [&](auto& v, auto& k) { return read_uint(v, k, 0, kU32, config.max_pinned_sends); }},
      {"blob_recheck_ms", [&](auto& v, auto& k) { return read_uint(v, k, 0, kU32, config.blob_recheck_ms); }},
      {"max_batch_cost", [&](auto& v, auto& k) { return read_uint(v, k, 0, kU64, config.max_batch_cost); }},
      {"query_wait_ms", [&](auto& v, auto& k) { return read_uint(v, k, 0, kU32, config.query_wait_ms); }},
      {"keep_alive_max_count",
       [&](auto& v, auto& k) { return read_uint(v, k, 0, kU32, config.keep_alive_max_count); }},
      {"keep_alive_timeout_s",
       [&](auto& v, auto& k) { return read_uint(v, k, 0, kU32, config.keep_alive_timeout_s); }},
      {"reload_poll_s", [&](auto& v, auto& k) { return read_uint(v, k, 0, kU32, config.reload_poll_s); }},
      {"leaflet_dir",
       [&](const nlohmann::json& v, const std::string& k) -> Status {
         if (!v.is_string()) return bad(k, "expected a string");
         config.leaflet_dir = v.get<std::string>();
         return {};
       }},
      {"render_threads", [&](auto& v, auto& k) { return read_uint(v, k, 0, kU32, config.render_threads); }},
      {"render_queue", [&](auto& v, auto& k) { return read_uint(v, k, 0, kU32, config.render_queue); }},
      {"render_timeout_ms", [&](auto& v, auto& k) { return read_uint(v, k, 0, kU32, config.render_timeout_ms); }},
      {"render_cache_bytes", [&](auto& v, auto& k) { return read_uint(v, k, 0, kU64, config.render_cache_bytes); }},
      {"replica_name",
       [&](const nlohmann::json& v, const std::string& k) -> Status {
         if (!v.is_string()) return bad(k, "expected a string");
         config.replica_name = v.get<std::string>();
         if (config.replica_name.find_first_of("\r\n") != std::string::npos) return bad(k, "must be one line");
         return {};
       }},
  };
  for (const auto& [key, value] : json.items()) {
    if (key.starts_with("_")) continue;  // "_comment" and friends: documentation inside the file
    auto reader = readers.find(key);
    if (reader == readers.end()) {
      std::string known;
      for (const auto& [name, unused] : readers) known += (known.empty() ? "" : ", ") + name;
      return make_error(ErrorCode::invalid_input, "unknown config key '" + key + "' (known: " + known + ")");
    }
    if (Status s = reader->second(value, key); !s) return s.error();
  }
  if (Status s = config.validate(); !s) return s.error();
  return config;
}

Result<ServerConfig> ServerConfig::from_json(const nlohmann::json& json) { return from_json(json, ServerConfig{}); }

Result<ServerConfig> ServerConfig::load(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec))
    return make_error(ErrorCode::not_found, "config file " + file.string() + " does not exist");
  std::ifstream in(file, std::ios::binary);
  if (!in) return make_error(ErrorCode::io_error, "cannot read config file " + file.string());
  std::stringstream text;
  text << in.rdbuf();
  auto json = nlohmann::json::parse(text.str(), nullptr, /*allow_exceptions=*/false, /*ignore_comments=*/true);
  if (json.is_discarded()) return make_error(ErrorCode::invalid_input, file.string() + ": not valid JSON");
  auto config = from_json(json);
  if (!config) return make_error(config.error().code, file.string() + ": " + config.error().message);
  return config;
}

}  // namespace shadowtiles::server
