#include "server/server.hpp"

#include <atomic>
#include <chrono>
#include <optional>

#include <httplib.h>
#include <spdlog/spdlog.h>

#include "client/shadow_map.hpp"
#include "server/connection_queue.hpp"
#include "server/http_response.hpp"
#include "server/routes_blobs.hpp"
#include "server/routes_info.hpp"
#include "server/routes_shadow.hpp"
#include "server/service_state.hpp"

namespace shadowtiles::server {
namespace {

// Start of the request being served on this thread: httplib serves one connection per worker
// thread, one request at a time, so a thread-local carries it from pre-routing to the logger.
thread_local std::optional<std::chrono::steady_clock::time_point> t_request_start;

const char* status_code_name(int status) {
  switch (status) {
    case 400: return "bad_request";
    case 403: return "forbidden";
    case 404: return "not_found";
    case 405: return "method_not_allowed";
    case 408: return "request_timeout";
    case 413: return "payload_too_large";
    case 414: return "uri_too_long";
    case 415: return "unsupported_media_type";
    case 416: return "range_not_satisfiable";
    case 503: return "unavailable";
    default: return status < 500 ? "bad_request" : "internal";
  }
}

}  // namespace

struct Server::Impl {
  explicit Impl(const ServerConfig& config) : state(config) {}
  ServiceState state;
  httplib::Server http;
  int port = 0;
  std::atomic<bool> stop_requested{false};
};

Server::Server(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Server::~Server() = default;

Result<std::unique_ptr<Server>> Server::bind(const ServerConfig& config) {
  if (Status s = config.validate(); !s) return s.error();
  auto impl = std::make_unique<Impl>(config);
  ServiceState& state = impl->state;
  httplib::Server& http = impl->http;

  const unsigned workers = config.threads, max_connections = config.max_connections;
  http.new_task_queue = [workers, max_connections] { return new ConnectionQueue(workers, max_connections); };
  http.set_read_timeout(time_t(config.read_timeout_s), 0);
  http.set_write_timeout(time_t(config.write_timeout_s), 0);
  http.set_keep_alive_max_count(config.keep_alive_max_count);
  http.set_keep_alive_timeout(time_t(config.keep_alive_timeout_s));
  http.set_payload_max_length(size_t(config.max_body_bytes));
  // httplib writes headers and body separately: with Nagle on, every keep-alive response would wait
  // for the client's delayed ACK (~40 ms).
  http.set_tcp_nodelay(true);

  http.set_pre_routing_handler([](const httplib::Request&, httplib::Response& res) {
    t_request_start = std::chrono::steady_clock::now();
    if (!ConnectionQueue::shedding()) return httplib::Server::HandlerResponse::Unhandled;
    res.set_header("Retry-After", "1");
    send_error(res, 503, "overloaded", "too many connections; retry later");
    return httplib::Server::HandlerResponse::Handled;
  });
  http.set_post_routing_handler([&state](const httplib::Request& req, httplib::Response& res) {
    state.cors.decorate(req, res);
  });
  // Errors the routes did not describe themselves (unknown path, body over the limit, malformed
  // request line) still get the JSON error shape.
  http.set_error_handler(httplib::Server::HandlerWithResponse([](const httplib::Request&, httplib::Response& res) {
    if (!res.body.empty()) return httplib::Server::HandlerResponse::Unhandled;
    std::string message = res.status == 404   ? "no such endpoint (see /v1/meta)"
                          : res.status == 413 ? "request body larger than the configured limit"
                          : res.status == 405 ? "method not allowed"
                          : res.status == 414 ? "request URI too long"
                                              : "the request was rejected (" + std::to_string(res.status) + ")";
    send_error(res, res.status, status_code_name(res.status), message);
    return httplib::Server::HandlerResponse::Handled;
  }));
  http.set_exception_handler([](const httplib::Request& req, httplib::Response& res, std::exception_ptr ep) {
    std::string what = "unknown exception";
    try {
      if (ep) std::rethrow_exception(ep);
    } catch (const std::exception& e) {
      what = e.what();
    } catch (...) {
    }
    spdlog::error("{} {}: handler failed: {}", req.method, req.path, what);
    send_error(res, 500, "internal", "internal error");
  });
  http.set_logger([&state](const httplib::Request& req, const httplib::Response& res) {
    std::optional<double> seconds;
    if (t_request_start) seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - *t_request_start).count();
    t_request_start.reset();
    state.metrics.observe(Metrics::route_of(req.path), req.method, res.status, seconds);
    spdlog::debug("{} {} {} {} {:.3f} ms", req.remote_addr, req.method, req.path, res.status,
                  seconds.value_or(0) * 1e3);
  });

  register_info_routes(http, state);
  register_shadow_routes(http, state);
  register_blob_routes(http, state);

  if (config.port == 0) {
    impl->port = http.bind_to_any_port(config.host);
    if (impl->port <= 0)
      return make_error(ErrorCode::io_error, "cannot bind " + config.host + " to an ephemeral port");
  } else {
    if (!http.bind_to_port(config.host, config.port))
      return make_error(ErrorCode::io_error,
                        "cannot bind " + config.host + ":" + std::to_string(config.port) + " (in use or not local?)");
    impl->port = config.port;
  }
  return std::unique_ptr<Server>(new Server(std::move(impl)));
}

int Server::port() const { return impl_->port; }
const ServerConfig& Server::config() const { return impl_->state.config; }

Status Server::attach_store(const std::filesystem::path& store_dir) {
  if (impl_->state.map()) return make_error(ErrorCode::invalid_input, "a store is already attached");
  ShadowMap::Options options;
  options.cache_bytes = size_t(impl_->state.config.cache_bytes);
  auto map = ShadowMap::open(store_dir, options);
  if (!map) return map.error();
  return attach(std::move(*map));
}

Status Server::attach(std::unique_ptr<ShadowMap> map) {
  if (!map) return make_error(ErrorCode::invalid_input, "no store to attach");
  if (!impl_->state.attach(std::move(map))) return make_error(ErrorCode::invalid_input, "a store is already attached");
  return {};
}

Status Server::run() {
  if (impl_->stop_requested.load()) return {};
  if (!impl_->http.listen_after_bind() && !impl_->stop_requested.load())
    return make_error(ErrorCode::io_error, "the HTTP listener failed");
  return {};
}

void Server::stop() {
  impl_->stop_requested.store(true);
  impl_->http.stop();
}

}  // namespace shadowtiles::server
