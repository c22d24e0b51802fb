#include "server/routes_blobs.hpp"

#include <atomic>
#include <memory>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "server/http_response.hpp"
#include "codec/store_meta.hpp"
#include "server/request_parsing.hpp"
#include "store/blob.hpp"
#include "store/tile_key.hpp"

namespace shadowtiles::server {
namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

// URLs carrying the build id never change meaning: cache them for good. Unversioned URLs name
// whatever build is served now, so caches must revalidate (the ETag makes that a cheap 304).
std::string cache_control(const ServiceState& state, bool versioned) {
  return versioned ? "public, max-age=" + std::to_string(state.config.cache_control_max_age) + ", immutable"
                   : "public, no-cache";
}

// Sets the validators of an answer (strong `etag`, Cache-Control by URL kind); true when the
// client's If-None-Match already names it, with 304 set and nothing more to send.
bool not_modified(const ServiceState& state, const httplib::Request& req, httplib::Response& res,
                  const std::string& etag, bool versioned) {
  res.set_header("ETag", etag);
  res.set_header("Cache-Control", cache_control(state, versioned));
  if (!req.has_header("If-None-Match") || !if_none_match_matches(req.get_header_value("If-None-Match"), etag))
    return false;
  res.status = 304;
  return true;
}

// A /v1/builds/{id}/... URL names the served build, or it is 404 (an older build after a swap).
bool check_build_id(const ShadowMap& map, const std::string& id, httplib::Response& res) {
  if (id == map.meta().config_hash) return true;
  send_error(res, 404, "not_found",
             "build '" + id + "' is not served here (the current build is '" + map.meta().config_hash +
                 "': see /v1/meta)");
  return false;
}

// Blob bodies sent straight from the store's map (no copy into the response) at once. Each holds
// an LMDB read transaction until its send ends; past config.max_pinned_sends, bodies are copied and
// the transaction ends with the handler, so slow clients cannot use up the store's 126 reader slots
// (max_connections may be set higher), which the query workers' tile reads need too.
std::atomic<unsigned> pinned_sends{0};

// A blob in the snapshot's map, kept valid (with the build that owns the store) while a send of it
// is in flight.
struct PinnedBlob {
  PinnedBlob(std::shared_ptr<const ShadowMap> m, store::Store::Snapshot s, std::span<const uint8_t> b)
      : map(std::move(m)), snapshot(std::move(s)), bytes(b) {
    pinned_sends.fetch_add(1, std::memory_order_relaxed);
  }
  ~PinnedBlob() { pinned_sends.fetch_sub(1, std::memory_order_relaxed); }
  PinnedBlob(const PinnedBlob&) = delete;
  PinnedBlob& operator=(const PinnedBlob&) = delete;
  std::shared_ptr<const ShadowMap> map;
  store::Store::Snapshot snapshot;
  std::span<const uint8_t> bytes;
};

// Sends the blob under `key` of `db` from `held`'s store, or calls on_absent. `what` names it in
// errors and logs.
template <class OnAbsent>
void serve_blob(ServiceState& state, std::shared_ptr<const ShadowMap> held, bool versioned,
                const httplib::Request& req, httplib::Response& res, store::Database db,
                std::span<const uint8_t> key, std::optional<store::Method> expected_method,
                const std::string& what, OnAbsent on_absent) {
  const ShadowMap& map = *held;
  set_build_header(res, map.meta().config_hash);
  const store::Store* store = map.local_store();
  if (!store) return send_error(res, 500, "internal", "the served build has no local store");
  auto snapshot = store->snapshot();
  if (!snapshot) {
    spdlog::error("{}: cannot read the store: {}", what, snapshot.error().message);
    return send_error(res, http_error_for(snapshot.error()));
  }
  auto view = snapshot->get_view(db, key);
  if (!view) {
    spdlog::error("{}: cannot read the store: {}", what, view.error().message);
    return send_error(res, http_error_for(view.error()));
  }
  if (!view->has_value()) return on_absent();
  // A check that passed lately stands (VerifiedBlobs says for how long and why that is safe).
  auto header = [&]() -> Result<store::BlobHeader> {
    if (auto recalled = state.verified_blobs.recall(held, db, key, **view)) return *recalled;
    auto checked = store::check_blob(**view);
    if (checked && expected_method && checked->method != *expected_method)
      return make_error(ErrorCode::corrupt_data, "the blob holds another method than its key");
    if (checked) state.verified_blobs.remember(held, db, key, **view, *checked);
    return checked;
  }();
  if (!header) {
    state.metrics.add_corrupt_blob();
    spdlog::error("{}: stored blob fails its checks, not served: {}", what, header.error().message);
    return send_error(res, 500, "corrupt_data", what + ": the stored blob fails its checks");
  }
  // fmt rather than string operator+: GCC 12 reports a false -Wrestrict on the latter.
  const std::string etag = fmt::format("\"{}\"", store::checksum_hex(header->checksum));
  if (not_modified(state, req, res, etag, versioned)) return;
  res.status = 200;
  const std::span<const uint8_t> bytes = **view;
  if (pinned_sends.load(std::memory_order_relaxed) >= state.config.max_pinned_sends) {
    res.set_content(reinterpret_cast<const char*>(bytes.data()), bytes.size(), "application/octet-stream");
    return;
  }
  // Zero-copy: the checked bytes go from the map to the socket (a copy into the response was 9 %
  // of a tile GET's CPU). The blob is the one just checked: the transaction pins its pages.
  auto pinned = std::make_shared<PinnedBlob>(std::move(held), std::move(*snapshot), bytes);
  res.set_content_provider(
      bytes.size(), "application/octet-stream",
      [pinned](size_t offset, size_t length, httplib::DataSink& sink) {
        return sink.write(reinterpret_cast<const char*>(pinned->bytes.data()) + offset, length);
      });  // the Response, which holds `pinned`, lives until the send has ended
}

// Tile URL captures start at `first` (after the build id, when the URL has one).
void get_tile(ServiceState& state, const httplib::Request& req, httplib::Response& res, bool versioned) {
  // No query slot: a blob read is bounded I/O-like work (a lookup in the mmap'd snapshot, the
  // blob's checksum and one copy), done on the connection's I/O thread like the send that follows.
  auto held = state.map();  // this request's build, even if a reload publishes another
  if (!held) return send_error(res, 503, "not_ready", "the store is not open yet");
  const ShadowMap& map = *held;
  const size_t first = versioned ? 2 : 1;
  if (versioned && !check_build_id(map, req.matches[1].str(), res)) return;
  auto method = store::parse_method(req.matches[first].str());
  if (!method) return send_error(res, 400, "invalid_input", "unknown method in the tile URL");
  uint64_t coords[3];
  static constexpr const char* kNames[3] = {"level", "x", "y"};
  for (size_t i = 0; i < 3; ++i) {
    auto value = parse_unsigned(req.matches[first + 1 + i].str(), kNames[i], UINT32_MAX);
    if (!value) return send_error(res, 400, "invalid_input", "tile URL: " + value.error().message);
    coords[i] = *value;
  }
  if (!map.meta().has_method(*method))
    return send_error(res, 404, "not_found", fmt::format("method '{}' is not in this store", store::method_name(*method)));
  const TileLayout& layout = map.layout();
  if (coords[0] != layout.tile_level())
    return send_error(res, 404, "not_found",
                      "this store has tiles at level " + std::to_string(layout.tile_level()) + " only");
  TileCoord coord{uint32_t(coords[1]), uint32_t(coords[2])};
  if (!layout.contains(coord))
    return send_error(res, 404, "not_found",
                      "tile outside the map (" + std::to_string(layout.tiles_per_side()) + " tiles per side)");
  auto key = store::encode_tile_key({*method, layout.tile_level(), coord.x, coord.y});
  std::string what = std::string("tile ") + store::method_name(*method) + "/" + std::to_string(coords[0]) + "/" +
                     std::to_string(coord.x) + "/" + std::to_string(coord.y);
  serve_blob(state, held, versioned, req, res, store::Database::tiles, key, *method, what, [&] {
    // In bounds, nothing stored: an empty tile (no geometry), lit everywhere.
    res.status = 204;
    res.set_header("Cache-Control", cache_control(state, versioned));
  });
}

void get_skiplist(ServiceState& state, const httplib::Request& req, httplib::Response& res, bool versioned) {
  auto held = state.map();  // no query slot, as for tiles
  if (!held) return send_error(res, 503, "not_ready", "the store is not open yet");
  const ShadowMap& map = *held;
  if (versioned && !check_build_id(map, req.matches[1].str(), res)) return;
  auto options = options_from_params(req.params, 1);
  if (!options) return send_error(res, http_error_for(options.error()));
  if (options->pcf || options->level || options->bias)
    return send_error(res, 400, "invalid_input", "/v1/skiplist takes only the 'method' parameter");
  store::Method method = options->method.value_or(map.default_method());
  if (!map.meta().has_method(method))
    return send_error(res, 404, "not_found", fmt::format("method '{}' is not in this store", store::method_name(method)));
  // The method's top tree: the tiles' root intervals with the skip list embedded.
  std::string key = top_tree_key(method);
  serve_blob(state, held, versioned, req, res, store::Database::top, store::as_bytes(key), method,
             std::string("skip list ") + store::method_name(method), [&] {
               send_error(res, 404, "not_found",
                          std::string("no skip list stored for method '") + store::method_name(method) +
                              "' (flat methods have none)");
             });
}

// The build's meta record exactly as stored: what a streaming client needs to map points to tiles.
void get_build(ServiceState& state, const httplib::Request& req, httplib::Response& res) {
  auto held = state.map();
  if (!held) return send_error(res, 503, "not_ready", "the store is not open yet");
  auto text = held->source().meta_text();
  if (!text) {
    spdlog::error("/v1/build: cannot read the store: {}", text.error().message);
    return send_error(res, http_error_for(text.error()));
  }
  auto parsed = StoreMeta::parse(*text);
  if (!parsed || parsed->config_hash != held->meta().config_hash) {
    // The directory's record no longer matches the build being served (a reload is pending).
    return send_error(res, 503, "not_ready", "the store's build record changed; retry after the reload");
  }
  set_build_header(res, held->meta().config_hash);
  const std::string etag = "\"" + held->meta().config_hash + "\"";
  if (not_modified(state, req, res, etag, false)) return;
  res.status = 200;
  res.set_content(*text, "application/json");
}

}  // namespace

bool if_none_match_matches(std::string_view header, std::string_view etag) {
  while (!header.empty()) {
    size_t comma = header.find(',');
    std::string_view tag = trim(header.substr(0, comma));
    header = comma == std::string_view::npos ? std::string_view{} : header.substr(comma + 1);
    if (tag == "*") return true;
    if (tag.starts_with("W/")) tag.remove_prefix(2);
    if (tag == etag) return true;
  }
  return false;
}

void register_blob_routes(httplib::Server& http, ServiceState& state) {
  http.Get(R"(/v1/tiles/([^/]+)/([^/]+)/([^/]+)/([^/]+))",
           [&state](const httplib::Request& req, httplib::Response& res) { get_tile(state, req, res, false); });
  http.Get(R"(/v1/builds/([^/]+)/tiles/([^/]+)/([^/]+)/([^/]+)/([^/]+))",
           [&state](const httplib::Request& req, httplib::Response& res) { get_tile(state, req, res, true); });
  http.Get("/v1/skiplist",
           [&state](const httplib::Request& req, httplib::Response& res) { get_skiplist(state, req, res, false); });
  http.Get(R"(/v1/builds/([^/]+)/skiplist)",
           [&state](const httplib::Request& req, httplib::Response& res) { get_skiplist(state, req, res, true); });
  http.Get("/v1/build", [&state](const httplib::Request& req, httplib::Response& res) { get_build(state, req, res); });
}

}  // namespace shadowtiles::server
