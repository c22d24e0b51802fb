#include "server/server.hpp"

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <system_error>
#include <thread>

#include <httplib.h>
#include <spdlog/spdlog.h>

#include "client/shadow_map.hpp"
#include "server/admission.hpp"
#include "server/connection_queue.hpp"
#include "server/http_response.hpp"
#include "server/http_service.hpp"
#include "server/request_parsing.hpp"
#include "server/routes_blobs.hpp"
#include "server/routes_info.hpp"
#include "server/routes_render.hpp"
#include "server/routes_shadow.hpp"
#include "server/service_state.hpp"
#include "store/serving_lock.hpp"

namespace shadowtiles::server {
namespace {

// Start of the request being served on this thread: each connection runs on its own I/O thread,
// one request at a time, so a thread-local carries it from pre-routing to the logger.
thread_local std::optional<std::chrono::steady_clock::time_point> t_request_start;

const char* status_code_name(int status) {
  switch (status) {
    case 400: return "bad_request";
    case 403: return "forbidden";
    case 404: return "not_found";
    case 405: return "method_not_allowed";
    case 408: return "request_timeout";
    case 411: return "length_required";
    case 431: return "header_fields_too_large";
    case 413: return "payload_too_large";
    case 414: return "uri_too_long";
    case 415: return "unsupported_media_type";
    case 416: return "range_not_satisfiable";
    case 503: return "unavailable";
    default: return status < 500 ? "bad_request" : "internal";
  }
}

ConnectionPolicy connection_policy(const ServerConfig& config) {
  ConnectionPolicy policy;
  policy.limits.header_timeout = std::chrono::seconds(config.read_timeout_s);
  policy.limits.body_timeout = std::chrono::seconds(config.body_timeout_s);
  policy.limits.write_timeout = std::chrono::seconds(config.write_timeout_s);
  policy.keep_alive_timeout = std::chrono::seconds(config.keep_alive_timeout_s);
  policy.keep_alive_max_count = config.keep_alive_max_count;
  policy.max_connections_per_address = config.max_connections_per_address;
  return policy;
}

struct Refusal {
  HttpError error;
  Metrics::Rejection reason;
};

// Checks a request on its headers alone, before its body is read: a declared body over
// max_body_bytes, a chunked body (not accepted: its size is unknown up front) or a binary batch over
// the point or cost limits is refused at once. The connection is then closed (the body stays unread).
std::optional<Refusal> refuse_before_body(const httplib::Request& req, const ServerConfig& config) {
  const bool has_body = req.method == "POST" || req.method == "PUT" || req.method == "PATCH";
  if (req.has_header("Transfer-Encoding") && has_body)
    return Refusal{{411, "length_required", "send the body with a Content-Length (chunked bodies are not accepted)"},
                   Metrics::Rejection::body_too_large};
  if (!req.has_header("Content-Length")) return std::nullopt;
  if (req.get_header_value_count("Content-Length") != 1)
    return Refusal{{400, "invalid_input", "Content-Length is given more than once"}, Metrics::Rejection::body_too_large};
  auto declared = parse_unsigned(req.get_header_value("Content-Length"), "Content-Length", UINT64_MAX);
  if (!declared) return Refusal{{400, "invalid_input", declared.error().message}, Metrics::Rejection::body_too_large};
  if (Status s = admit_body(*declared, config); !s)
    return Refusal{{413, "payload_too_large", s.error().message}, Metrics::Rejection::body_too_large};
  if (req.method == "POST" && req.path == "/v1/shadow" &&
      media_type(req.get_header_value("Content-Type")) == "application/octet-stream") {
    unsigned pcf = 0;
    if (req.get_param_value_count("pcf") == 1) {
      auto k = parse_unsigned(req.get_param_value("pcf"), "pcf", UINT32_MAX);
      if (k) pcf = unsigned(*k);  // a bad value is the handler's 400
    }
    if (Status s = admit_batch(*declared / 12, pcf, config); !s)
      return Refusal{{413, *declared / 12 > config.max_batch_points ? "too_many_points" : "batch_too_costly",
                      s.error().message},
                     Metrics::Rejection::batch_too_costly};
  }
  return std::nullopt;
}

uint64_t declared_body_bytes(const httplib::Request& req) {
  auto declared = parse_unsigned(req.get_header_value("Content-Length"), "Content-Length", UINT64_MAX);
  return declared ? *declared : 0;
}

}  // namespace

// A served build: the map and the shared serving lock that keeps builders out of its directory.
// Published as a shared_ptr<const ShadowMap> aliasing this, so the lock lives exactly as long as
// some request still reads the build.
struct ServedBuild {
  store::ServingLock lock;
  std::unique_ptr<ShadowMap> map;
  std::filesystem::path dir;  // canonical
};

struct Server::Impl {
  explicit Impl(const ServerConfig& config) : state(config), http(connection_policy(config), state.metrics) {}
  ServiceState state;
  HttpService http;
  int port = 0;
  std::atomic<bool> stop_requested{false};

  // Reloads (attach_store, reload, the poller) are serialised by reload_mutex.
  std::mutex reload_mutex;
  std::filesystem::path store_path;   // as given: may be a symlink a deployment repoints
  std::filesystem::path served_dir;   // canonical directory of the published build
  std::weak_ptr<const ShadowMap> previous;  // the build replaced last, while requests still hold it

  std::mutex poll_mutex;
  std::condition_variable poll_wake;
  bool poll_stop = false;
  std::thread poller;

  Result<std::shared_ptr<const ShadowMap>> open_build(const std::filesystem::path& dir) const;
  Result<bool> reload_locked();
};

Server::Server(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Server::~Server() {
  {
    std::lock_guard lock(impl_->poll_mutex);
    impl_->poll_stop = true;
  }
  impl_->poll_wake.notify_all();
  if (impl_->poller.joinable()) impl_->poller.join();
}

Result<std::shared_ptr<const ShadowMap>> Server::Impl::open_build(const std::filesystem::path& dir) const {
  auto lock = store::ServingLock::acquire(dir, store::ServingLock::Kind::serve);
  if (!lock) return lock.error();
  ShadowMap::Options options;
  options.cache_bytes = size_t(state.config.cache_bytes);
  auto map = ShadowMap::open(dir, options);
  if (!map) return map.error();
  auto served = std::make_shared<ServedBuild>(ServedBuild{std::move(*lock), std::move(*map), dir});
  const ShadowMap* raw = served->map.get();
  return std::shared_ptr<const ShadowMap>(std::move(served), raw);
}

// True when a new build was published. The store path is resolved again each time, so repointing
// a symlink (ln -sfn new current) swaps builds; the same directory with a new build record (it
// cannot change while we hold the serving lock, unless a writer ignores it) is reopened too.
Result<bool> Server::Impl::reload_locked() {
  if (store_path.empty()) return make_error(ErrorCode::invalid_input, "no store path to reload from");
  std::error_code ec;
  std::filesystem::path dir = std::filesystem::canonical(store_path, ec);
  if (ec) return make_error(ErrorCode::not_found, "cannot resolve " + store_path.string() + ": " + ec.message());
  auto current = state.map();
  if (current && dir == served_dir) {
    auto text = current->source().meta_text();
    if (!text) return text.error();
    auto meta = StoreMeta::parse(*text);
    if (!meta) return meta.error();
    if (meta->config_hash == current->meta().config_hash) return false;
    return make_error(ErrorCode::invalid_input,
                      dir.string() + " was rewritten in place while served; serving the old snapshot until restart");
  }
  // One LMDB environment per directory and process: a directory still open for draining requests
  // (swapped away from a moment ago) cannot be opened again yet.
  if (auto draining = previous.lock(); draining && current && draining != current) {
    if (const store::Store* st = draining->local_store(); st && std::filesystem::equivalent(st->path(), dir, ec))
      return make_error(ErrorCode::invalid_input, dir.string() + " is still draining its previous requests; retry");
  }
  auto opened = open_build(dir);
  if (!opened) return opened.error();
  previous = current;
  state.publish(std::move(*opened));
  served_dir = dir;
  spdlog::info("serving build {} from {}", state.map()->meta().config_hash, dir.string());
  return true;
}

Result<std::unique_ptr<Server>> Server::bind(const ServerConfig& config) {
  if (Status s = config.validate(); !s) return s.error();
  auto impl = std::make_unique<Impl>(config);
  ServiceState& state = impl->state;
  HttpService& http = impl->http;

  // Connection I/O on up to max_connections I/O threads; query work under `threads` query slots
  // (ServiceState::slots). Deadlines are HttpService's (ConnectionStream), not httplib's per-read
  // timeouts; the payload limit stays as a second guard.
  const unsigned max_connections = config.max_connections;
  http.new_task_queue = [max_connections] { return new ConnectionQueue(max_connections); };
  http.set_payload_max_length(size_t(config.max_body_bytes));

  http.set_expect_100_continue_handler([&state](const httplib::Request& req, httplib::Response& res) {
    if (auto refusal = refuse_before_body(req, state.config)) {
      state.metrics.add_rejection(refusal->reason);
      send_error(res, refusal->error);
      HttpService::close_after_response();
      return refusal->error.status;  // httplib answers it; the body is never read
    }
    return 100;
  });
  http.set_pre_routing_handler([&state](const httplib::Request& req, httplib::Response& res) {
    t_request_start = std::chrono::steady_clock::now();
    if (auto refusal = refuse_before_body(req, state.config)) {
      state.metrics.add_rejection(refusal->reason);
      send_error(res, refusal->error);
      res.set_header("Connection", "close");
      HttpService::close_after_response();
      return httplib::Server::HandlerResponse::Handled;
    }
    if (ConnectionStream* stream = HttpService::current()) stream->begin_body(declared_body_bytes(req));
    return httplib::Server::HandlerResponse::Unhandled;
  });
  // Behind a proxy with several replicas, every answer says which replica gave it.
  std::string replica = config.replica_name;
  if (replica.empty()) {
    char host[256] = {};
    gethostname(host, sizeof host - 1);
    replica = std::string(host) + ":" + std::to_string(config.port);
  }
  http.set_post_routing_handler([&state, replica](const httplib::Request& req, httplib::Response& res) {
    state.cors.decorate(req, res);
    res.set_header("X-Shadow-Replica", replica);
  });
  // Errors the routes did not describe themselves (unknown path, body over the limit, malformed
  // request line) still get the JSON error shape.
  http.set_error_handler(httplib::Server::HandlerWithResponse([](const httplib::Request&, httplib::Response& res) {
    // httplib reports a read cut short by our deadline as a malformed request (400).
    if (ConnectionStream* stream = HttpService::current();
        stream && (stream->expired() == ConnectionStream::Phase::headers ||
                   stream->expired() == ConnectionStream::Phase::body)) {
      if (stream->over_cap())
        send_error(res, 431, "header_fields_too_large", "the request line and headers exceed 64 KiB");
      else
        send_error(res, 408, "request_timeout",
                 stream->expired() == ConnectionStream::Phase::headers
                     ? "the request headers did not arrive within read_timeout_s"
                     : "the request body did not arrive within body_timeout_s");
      res.set_header("Connection", "close");
      return httplib::Server::HandlerResponse::Handled;
    }
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
  register_render_routes(http, state);

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
  http.widen_listen_backlog();
  return std::unique_ptr<Server>(new Server(std::move(impl)));
}

int Server::port() const { return impl_->port; }
const ServerConfig& Server::config() const { return impl_->state.config; }

Status Server::attach_store(const std::filesystem::path& store_dir) {
  std::lock_guard lock(impl_->reload_mutex);
  if (impl_->state.map() || !impl_->store_path.empty())
    return make_error(ErrorCode::invalid_input, "a store is already attached");
  impl_->store_path = store_dir;
  auto loaded = impl_->reload_locked();
  if (impl_->state.config.reload_poll_s > 0) {
    // Polls even when the first open failed (a build still being written): it is served once done.
    impl_->poller = std::thread([impl = impl_.get()] {
      std::unique_lock lock(impl->poll_mutex);
      while (!impl->poll_wake.wait_for(lock, std::chrono::seconds(impl->state.config.reload_poll_s),
                                       [impl] { return impl->poll_stop; })) {
        lock.unlock();
        {
          std::lock_guard reload_lock(impl->reload_mutex);
          auto reloaded = impl->reload_locked();
          if (!reloaded) spdlog::debug("reload check: {}", reloaded.error().message);
        }
        lock.lock();
      }
    });
  }
  if (!loaded) return loaded.error();
  return {};
}

Result<bool> Server::reload() {
  std::lock_guard lock(impl_->reload_mutex);
  return impl_->reload_locked();
}

Status Server::attach(std::unique_ptr<ShadowMap> map) {
  if (!map) return make_error(ErrorCode::invalid_input, "no store to attach");
  std::lock_guard lock(impl_->reload_mutex);
  if (impl_->state.map() || !impl_->store_path.empty())
    return make_error(ErrorCode::invalid_input, "a store is already attached");
  impl_->state.publish(std::shared_ptr<const ShadowMap>(std::move(map)));
  return {};
}

std::string Server::build_id() const {
  auto map = impl_->state.map();
  return map ? map->meta().config_hash : std::string();
}

void Server::serve_connection(int fd) { impl_->http.serve_socket(fd); }

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
