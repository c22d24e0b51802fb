#include "server/routes_shadow.hpp"

#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <optional>

#include <spdlog/spdlog.h>

#include "server/admission.hpp"
#include "server/http_response.hpp"
#include "server/shadow_query.hpp"

namespace shadowtiles::server {
namespace {

constexpr const char* kBinaryType = "application/octet-stream";

// Every answer names the store's receiver contract (docs/receiver-contracts.md): under `surfaces` a
// point off every surface gets only a bounded answer, so a caller must be able to tell.
const char* receivers_of(const ShadowMap& map) { return receiver_contract_name(map.meta().receivers); }

bool require_map(const ServiceState& state, httplib::Response& res) {
  if (state.map()) return true;
  send_error(res, 503, "not_ready", "the store is not open yet");
  return false;
}

void get_shadow(ServiceState& state, const httplib::Request& req, httplib::Response& res) {
  if (!require_map(state, res)) return;
  auto held = state.map();  // this request's build, even if a reload publishes another
  const ShadowMap& map = *held;
  set_build_header(res, map.meta().config_hash);
  // Parsing and the JSON answer are the I/O thread's; only the decoding holds a query slot, so a
  // slot is held for microseconds and waiters behind it move on quickly.
  static constexpr std::string_view kPointParams[] = {"x", "y", "z"};
  auto options = options_from_params(req.params, state.config.max_pcf, kPointParams);
  if (!options) return send_error(res, http_error_for(options.error()));
  auto point = point_from_params(req.params);
  if (!point) return send_error(res, http_error_for(point.error()));
  auto query = resolve_query(map, *options);
  if (!query) return send_error(res, http_error_for(query.error()));
  auto result = [&]() -> std::optional<Result<PointResult>> {
    auto slot = take_query_slot(state, res);
    if (!slot) return std::nullopt;
    return answer_point(map, *point, *query);
  }();
  if (!result) return;  // 503 busy, sent
  if (!*result) return send_error(res, http_error_for(result->error()));
  state.metrics.add_points(1);
  const PointResult& answered = **result;
  const ShadowAnswer& a = answered.answer;
  auto finite_or_null = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  send_json(res, 200,
            {{"lit", answered.lit},
             {"shadowed", query->pcf == 0 ? !a.lit : answered.lit <= 0.5},
             {"outside_map", a.outside_map},
             {"empty_tile", a.empty_tile},
             {"u", finite_or_null(a.light.u)},
             {"v", finite_or_null(a.light.v)},
             {"depth", finite_or_null(a.light.depth)},
             {"method", store::method_name(query->method)},
             {"receivers", receivers_of(map)},
             {"pcf", query->pcf == 0 ? 1u : query->pcf}});
}

void post_json(ServiceState& state, const ShadowMap& map, const httplib::Request& req, httplib::Response& res) {
  if (!req.params.empty())
    return send_error(res, 400, "invalid_input", "a JSON batch takes its options in the body, not the query string");
  auto batch = parse_json_batch(req.body, state.config.max_pcf, state.config.max_batch_points);
  if (!batch) {
    if (batch.error().code == ErrorCode::out_of_space)
      return send_error(res, 413, "too_many_points", batch.error().message);
    return send_error(res, http_error_for(batch.error()));
  }
  if (Status admitted = admit_batch(batch->points.size(), batch->options.pcf, state.config); !admitted) {
    state.metrics.add_rejection(Metrics::Rejection::batch_too_costly);
    return send_error(res, 413, "batch_too_costly", admitted.error().message);
  }
  auto query = resolve_query(map, batch->options);
  if (!query) return send_error(res, http_error_for(query.error()));
  auto result = answer_batch(map, batch->points, *query, state.pool);
  if (!result) return send_error(res, http_error_for(result.error()));
  state.metrics.add_points(batch->points.size());
  nlohmann::json lit = nlohmann::json::array();
  lit.get_ref<nlohmann::json::array_t&>().reserve(result->lit.size());
  for (float v : result->lit) lit.push_back(double(v));
  send_json(res, 200,
            {{"lit", std::move(lit)},
             {"outside_map", result->outside},
             {"count", batch->points.size()},
             {"method", store::method_name(query->method)},
             {"receivers", receivers_of(map)},
             {"pcf", query->pcf == 0 ? 1u : query->pcf}});
}

void post_binary(ServiceState& state, const ShadowMap& map, const httplib::Request& req, httplib::Response& res) {
  auto options = options_from_params(req.params, state.config.max_pcf);
  if (!options) return send_error(res, http_error_for(options.error()));
  if (req.body.size() / 12 > state.config.max_batch_points)
    return send_error(res, 413, "too_many_points",
                      "more than " + std::to_string(state.config.max_batch_points) + " points in one batch");
  if (Status admitted = admit_batch(req.body.size() / 12, options->pcf, state.config); !admitted) {
    state.metrics.add_rejection(Metrics::Rejection::batch_too_costly);
    return send_error(res, 413, "batch_too_costly", admitted.error().message);
  }
  auto points = points_from_binary({reinterpret_cast<const uint8_t*>(req.body.data()), req.body.size()});
  if (!points) return send_error(res, http_error_for(points.error()));
  auto query = resolve_query(map, *options);
  if (!query) return send_error(res, http_error_for(query.error()));
  auto start = std::chrono::steady_clock::now();
  auto result = answer_batch(map, *points, *query, state.pool);
  if (!result) return send_error(res, http_error_for(result.error()));
  spdlog::debug("binary batch: {} points answered in {:.2f} ms", points->size(),
                std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  state.metrics.add_points(points->size());
  std::string body(result->lit.size() * 4, '\0');
  if constexpr (std::endian::native == std::endian::little) {
    // An empty batch has no answer buffer (data() may be null, which memcpy must not get).
    if (!body.empty()) std::memcpy(body.data(), result->lit.data(), body.size());  // the wire order already
  } else {
    for (size_t i = 0; i < result->lit.size(); ++i) {
      uint32_t bits = std::bit_cast<uint32_t>(result->lit[i]);
      for (int b = 0; b < 4; ++b) body[i * 4 + b] = char((bits >> (8 * b)) & 0xff);  // little-endian on the wire
    }
  }
  res.status = 200;
  res.set_header("X-Shadow-Outside-Map", std::to_string(result->outside.size()));
  res.set_header("X-Shadow-Receivers", receivers_of(map));
  res.set_content(std::move(body), kBinaryType);
}

void post_shadow(ServiceState& state, const httplib::Request& req, httplib::Response& res) {
  if (!require_map(state, res)) return;
  auto slot = take_query_slot(state, res);  // parsing a large body is query work too
  if (!slot) return;
  // One build answers the whole batch, even if a reload publishes another meanwhile.
  auto held = state.map();
  if (!held) return send_error(res, 503, "not_ready", "the store is not open yet");
  set_build_header(res, held->meta().config_hash);
  std::string type = media_type(req.get_header_value("Content-Type"));
  if (type == "application/json") return post_json(state, *held, req, res);
  if (type == kBinaryType) return post_binary(state, *held, req, res);
  send_error(res, 415, "unsupported_media_type",
             "Content-Type must be application/json or application/octet-stream (float32 x, y, z triples)");
}

}  // namespace

void register_shadow_routes(httplib::Server& http, ServiceState& state) {
  http.Get("/v1/shadow", [&state](const httplib::Request& req, httplib::Response& res) { get_shadow(state, req, res); });
  http.Post("/v1/shadow", [&state](const httplib::Request& req, httplib::Response& res) { post_shadow(state, req, res); });
}

}  // namespace shadowtiles::server
