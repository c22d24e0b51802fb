#include "server/routes_info.hpp"

#include "server/http_response.hpp"
#include "server/meta_document.hpp"

namespace shadowtiles::server {

void register_info_routes(httplib::Server& http, ServiceState& state) {
  http.Get("/v1/meta", [&state](const httplib::Request&, httplib::Response& res) {
    auto map = state.map();
    if (!map) return send_error(res, 503, "not_ready", "the store is not open yet");
    send_json(res, 200, meta_document(*map));
    set_build_header(res, map->meta().config_hash);
    // The document changes only with the store; a short max-age lets clients skip refetching it.
    res.set_header("Cache-Control", "public, max-age=60");
  });
  http.Get("/healthz", [&state](const httplib::Request&, httplib::Response& res) {
    auto map = state.map();
    if (!map)
      return send_json(res, 503, {{"status", "starting"}, {"error", "the store is not open yet"}, {"code", "not_ready"}});
    send_json(res, 200, {{"status", "ok"}, {"build_id", map->meta().config_hash}});
    set_build_header(res, map->meta().config_hash);
    res.set_header("Cache-Control", "no-store");
  });
  http.Get("/metrics", [&state](const httplib::Request&, httplib::Response& res) {
    auto map = state.map();
    std::optional<CacheStats> cache;
    if (map) cache = map->cache_stats();
    res.status = 200;
    res.set_content(state.metrics.render(cache), "text/plain; version=0.0.4; charset=utf-8");
    res.set_header("Cache-Control", "no-store");
  });
  http.Options(".*", [&state](const httplib::Request& req, httplib::Response& res) { state.cors.answer_options(req, res); });
  auto not_allowed = [](const httplib::Request&, httplib::Response& res) {
    res.set_header("Allow", "GET, HEAD, POST, OPTIONS");
    send_error(res, 405, "method_not_allowed", "this API accepts GET, HEAD, POST and OPTIONS only");
  };
  http.Put(".*", not_allowed);
  http.Patch(".*", not_allowed);
  http.Delete(".*", not_allowed);
}

}  // namespace shadowtiles::server
