#include "server/routes_render.hpp"

#include <xxhash.h>

#include <time.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <future>
#include <sstream>

#include <spdlog/spdlog.h>

#include "server/http_response.hpp"
#include "server/inspector_assets.hpp"
#include "server/request_parsing.hpp"
#include "server/tile_renderer.hpp"
#include "store/blob.hpp"

namespace shadowtiles::server {
namespace {

std::string cache_control(const ServiceState& state, bool versioned) {
  return versioned ? "public, max-age=" + std::to_string(state.config.cache_control_max_age) + ", immutable"
                   : "public, no-cache";
}

bool etag_matches(const httplib::Request& req, const std::string& etag) {
  if (!req.has_header("If-None-Match")) return false;
  std::string header = req.get_header_value("If-None-Match");
  return header == "*" || header.find(etag) != std::string::npos;
}

// Exactly the listed parameters, each at most once.
bool check_params(const httplib::Request& req, std::initializer_list<std::string_view> allowed, httplib::Response& res) {
  for (const auto& [key, value] : req.params) {
    if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
      send_error(res, 400, "invalid_input", "unknown parameter '" + key.substr(0, 40) + "'");
      return false;
    }
    if (req.params.count(key) > 1) {
      send_error(res, 400, "invalid_input", "parameter '" + key + "' given more than once");
      return false;
    }
  }
  return true;
}

std::optional<store::Method> method_in_store(const ShadowMap& map, const std::string& name, httplib::Response& res) {
  auto method = store::parse_method(name);
  if (!method) {
    send_error(res, 400, "invalid_input", "unknown method '" + name.substr(0, 20) + "'");
    return std::nullopt;
  }
  if (!map.meta().has_method(*method)) {
    send_error(res, 404, "not_found", std::string("method '") + store::method_name(*method) + "' is not in this store");
    return std::nullopt;
  }
  return *method;
}

void get_render(ServiceState& state, const httplib::Request& req, httplib::Response& res, bool versioned) {
  auto held = state.map();
  if (!held) return send_error(res, 503, "not_ready", "the store is not open yet");
  const ShadowMap& map = *held;
  set_build_header(res, map.meta().config_hash);
  const size_t first = versioned ? 2 : 1;
  if (versioned && req.matches[1].str() != map.meta().config_hash)
    return send_error(res, 404, "not_found", "build '" + req.matches[1].str().substr(0, 40) + "' is not served here");
  if (!map.local_store()) return send_error(res, 404, "not_found", "rendering needs a local store");
  auto method = method_in_store(map, req.matches[first].str(), res);
  if (!method) return;
  uint64_t coords[3];
  static constexpr const char* kNames[3] = {"z", "x", "y"};
  for (size_t i = 0; i < 3; ++i) {
    auto value = parse_unsigned(req.matches[first + 1 + i].str(), kNames[i], UINT32_MAX);
    if (!value) return send_error(res, 400, "invalid_input", "render URL: " + value.error().message);
    coords[i] = *value;
  }
  if (!check_params(req, {"layer", "against"}, res)) return;
  RenderRequest request;
  request.method = *method;
  if (req.has_param("layer")) {
    auto layer = parse_render_layer(req.get_param_value("layer"));
    if (!layer) return send_error(res, 400, "invalid_input", layer.error().message);
    request.layer = *layer;
  }
  if (req.has_param("against")) {
    if (request.layer != RenderLayer::diff)
      return send_error(res, 400, "invalid_input", "'against' is for layer=diff only");
    auto against = method_in_store(map, req.get_param_value("against"), res);
    if (!against) return;
    request.against = *against;
  } else if (request.layer == RenderLayer::diff) {
    return send_error(res, 400, "invalid_input", "layer=diff needs against=METHOD");
  }
  const unsigned max_zoom = max_render_zoom(map.layout().resolution());
  if (coords[0] > max_zoom)
    return send_error(res, 404, "not_found", "zoom beyond " + std::to_string(max_zoom) + ", the finest for this map");
  request.z = unsigned(coords[0]);
  if (coords[1] >> request.z || coords[2] >> request.z)
    return send_error(res, 404, "not_found", "x and y must be below 2^z at zoom " + std::to_string(request.z));
  request.x = uint32_t(coords[1]);
  request.y = uint32_t(coords[2]);

  std::string identity = map.meta().config_hash + "|" + std::to_string(kRendererVersion) + "|" +
                         store::method_name(request.method) + "|" + render_layer_name(request.layer) + "|" +
                         (request.against ? store::method_name(*request.against) : "") + "|" +
                         std::to_string(request.z) + "/" + std::to_string(request.x) + "/" + std::to_string(request.y);
  const std::string etag = "\"r" + store::checksum_hex(XXH64(identity.data(), identity.size(), 0)) + "\"";
  res.set_header("ETag", etag);
  res.set_header("Cache-Control", cache_control(state, versioned));
  if (etag_matches(req, etag)) {
    res.status = 304;
    return;
  }

  struct Rendered {
    std::optional<Result<RenderOutput>> output;
    std::string png;
    double wall_ms = 0, cpu_ms = 0;  // on the render thread: what the request cost apart from queueing
  };
  auto budget = std::chrono::milliseconds(state.config.render_timeout_ms);
  auto deadline = std::chrono::steady_clock::now() + budget;
  auto promise = std::make_shared<std::promise<Rendered>>();
  auto future = promise->get_future();
  ServiceState* st = &state;
  bool queued = state.render_pool.try_submit([promise, held, request, deadline, st] {
    Rendered r;
    auto wall_start = std::chrono::steady_clock::now();
    timespec cpu_start{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &cpu_start);
    r.output = render_map_tile(*held, st->render_cache, request, deadline);
    if (r.output->ok() && !(*r.output)->timed_out) {
      auto png = encode_png((*r.output)->image);
      if (png) r.png = std::move(*png);
      else r.output = png.error();
      (*r.output)->image = RgbaImage();  // the PNG is what travels back
    }
    timespec cpu_end{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &cpu_end);
    r.cpu_ms = double(cpu_end.tv_sec - cpu_start.tv_sec) * 1e3 + double(cpu_end.tv_nsec - cpu_start.tv_nsec) / 1e6;
    r.wall_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - wall_start).count();
    promise->set_value(std::move(r));
  });
  if (!queued) {
    res.set_header("Retry-After", "1");
    return send_error(res, 503, "overloaded", "the render queue is full; retry later");
  }
  if (future.wait_for(budget + std::chrono::milliseconds(500)) != std::future_status::ready) {
    res.set_header("Retry-After", "2");
    return send_error(res, 503, "render_timeout", "rendering took longer than render_timeout_ms");
  }
  Rendered r = future.get();
  if (!r.output->ok()) {
    spdlog::error("render {}: {}", identity, r.output->error().message);
    if (r.output->error().code == ErrorCode::corrupt_data) state.metrics.add_corrupt_blob();
    return send_error(res, http_error_for(r.output->error()));
  }
  if ((*r.output)->timed_out) {
    res.set_header("Retry-After", "2");
    return send_error(res, 503, "render_timeout", "rendering took longer than render_timeout_ms");
  }
  if (unsigned corrupt = (*r.output)->corrupt_tiles) {
    for (unsigned i = 0; i < corrupt; ++i) state.metrics.add_corrupt_blob();
    res.set_header("X-Shadowtiles-Corrupt-Tiles", std::to_string(corrupt));
    res.set_header("Cache-Control", "no-store");  // a picture of damage must not be kept
  }
  res.set_header("X-Shadowtiles-Source", (*r.output)->decoded_tiles ? "tiles" : "previews");
  char timing[96];
  std::snprintf(timing, sizeof timing, "render;dur=%.2f, cpu;dur=%.2f", r.wall_ms, r.cpu_ms);
  res.set_header("Server-Timing", timing);
  res.status = 200;
  res.set_content(std::move(r.png), "image/png");
}

void get_texel(ServiceState& state, const httplib::Request& req, httplib::Response& res) {
  auto held = state.map();
  if (!held) return send_error(res, 503, "not_ready", "the store is not open yet");
  const ShadowMap& map = *held;
  if (!check_params(req, {"u", "v"}, res)) return;
  if (!req.has_param("u") || !req.has_param("v")) return send_error(res, 400, "invalid_input", "give u and v");
  const uint32_t R = map.layout().resolution();
  auto u = parse_unsigned(req.get_param_value("u"), "u", UINT32_MAX);
  auto v = parse_unsigned(req.get_param_value("v"), "v", UINT32_MAX);
  if (!u || !v) return send_error(res, 400, "invalid_input", (!u ? u.error() : v.error()).message);
  if (*u >= R || *v >= R) return send_error(res, 404, "not_found", "texel outside the map (" + std::to_string(R) + " per side)");
  const uint32_t T = map.layout().tile_size();
  TileCoord tile{uint32_t(*u / T), uint32_t(*v / T)};
  nlohmann::json methods = nlohmann::json::array();
  std::optional<float> surface;
  for (store::Method method : map.meta().methods) {
    auto value = map.texel_value(method, uint32_t(*u), uint32_t(*v));
    if (!value) {
      if (value.error().code == ErrorCode::corrupt_data) state.metrics.add_corrupt_blob();
      return send_error(res, http_error_for(value.error()));
    }
    nlohmann::json entry = {{"method", store::method_name(method)}, {"value", *value < 1.0f ? nlohmann::json(*value) : nullptr},
                            {"miss", !(*value < 1.0f)}};
    if (*value < 1.0f) entry["depth_world"] = double(*value) * map.frame().depth_range();
    if (map.local_store()) {
      auto summary = state.render_cache.get(map, method, tile);
      if (!summary) return send_error(res, http_error_for(summary.error()));
      entry["tile_bytes"] = (*summary)->blob_bytes;
      entry["tile_bits_per_texel"] = double((*summary)->blob_bytes) * 8.0 / (double(T) * T);
    }
    if (!surface && *value < 1.0f && !store::method_properties(method).stores_visibility) surface = *value;
    methods.push_back(std::move(entry));
  }
  nlohmann::json body = {{"u", *u}, {"v", *v},
                         {"tile", {{"level", map.layout().tile_level()}, {"x", tile.x}, {"y", tile.y}}},
                         {"methods", methods}};
  if (surface) {
    Vec3 w = map.frame().to_world({double(*u) + 0.5, double(*v) + 0.5, double(*surface)});
    body["surface_world"] = {w[0], w[1], w[2]};
  }
  send_json(res, 200, body);
  res.set_header("Cache-Control", "no-cache");
}

void send_asset(httplib::Response& res, const InspectorAsset& asset) {
  res.status = 200;
  res.set_content(std::string(asset.bytes), asset.content_type);
  res.set_header("Cache-Control", "no-cache");
}

// Debian's libjs-leaflet files, read from leaflet_dir (names are matched against a fixed list).
void send_leaflet(ServiceState& state, const std::string& name, httplib::Response& res) {
  static const std::map<std::string, std::string> kFiles = {
      {"leaflet.js", "application/javascript"}, {"leaflet.css", "text/css"},
      {"images/layers.png", "image/png"},       {"images/layers-2x.png", "image/png"},
      {"images/marker-icon.png", "image/png"},  {"images/marker-icon-2x.png", "image/png"},
      {"images/marker-shadow.png", "image/png"}};
  auto it = kFiles.find(name);
  if (it == kFiles.end()) return send_error(res, 404, "not_found", "no such inspector file");
  std::ifstream in(std::filesystem::path(state.config.leaflet_dir) / name, std::ios::binary);
  if (!in)
    return send_error(res, 404, "not_found",
                      "Leaflet is not installed at " + state.config.leaflet_dir + " (apt-get install libjs-leaflet)");
  std::ostringstream text;
  text << in.rdbuf();
  res.status = 200;
  res.set_content(text.str(), it->second);
  res.set_header("Cache-Control", "public, max-age=3600");
}

}  // namespace

void register_render_routes(httplib::Server& http, ServiceState& state) {
  http.Get(R"(/v1/render/legend)", [&state](const httplib::Request& req, httplib::Response& res) {
    auto held = state.map();
    if (!held) return send_error(res, 503, "not_ready", "the store is not open yet");
    if (!check_params(req, {"layer"}, res)) return;
    auto layer = parse_render_layer(req.has_param("layer") ? req.get_param_value("layer") : "value");
    if (!layer) return send_error(res, 400, "invalid_input", layer.error().message);
    send_json(res, 200, render_legend(*held, *layer));
  });
  http.Get(R"(/v1/render/([^/]+)/([^/]+)/([^/]+)/([^/]+)\.png)",
           [&state](const httplib::Request& req, httplib::Response& res) { get_render(state, req, res, false); });
  http.Get(R"(/v1/builds/([^/]+)/render/([^/]+)/([^/]+)/([^/]+)/([^/]+)\.png)",
           [&state](const httplib::Request& req, httplib::Response& res) { get_render(state, req, res, true); });
  http.Get("/v1/texel", [&state](const httplib::Request& req, httplib::Response& res) { get_texel(state, req, res); });
  auto page = [](const httplib::Request&, httplib::Response& res) { send_asset(res, inspector_asset("index.html")); };
  http.Get("/", page);
  http.Get("/inspector/", page);
  http.Get("/inspector", [](const httplib::Request&, httplib::Response& res) { res.set_redirect("/inspector/"); });
  http.Get(R"(/inspector/leaflet/(.+))", [&state](const httplib::Request& req, httplib::Response& res) {
    send_leaflet(state, req.matches[1].str(), res);
  });
  http.Get(R"(/inspector/([a-z]+\.(js|css)))", [](const httplib::Request& req, httplib::Response& res) {
    const InspectorAsset& asset = inspector_asset(req.matches[1].str());
    if (asset.bytes.empty()) return send_error(res, 404, "not_found", "no such inspector file");
    send_asset(res, asset);
  });
}

}  // namespace shadowtiles::server
