// `shadowtiles serve [STORE]` (or the config's "store" key): the HTTP shadow service (server/server.hpp; API and config keys in
// config/README.md). Config: defaults, then --config FILE, then the flags given on the command line.
// SIGTERM / SIGINT stop accepting, drain in-flight requests and exit 0. SIGHUP (and a poll every
// reload_poll_s) swaps to a new build at the store path (server/server.hpp, "Swapping builds").
#include <cstdio>
#include <iostream>
#include <memory>
#include <mutex>
#include <optional>

#include <spdlog/spdlog.h>

#include "cli/commands.hpp"
#include "cli/exit_codes.hpp"
#include "server/allocator_tuning.hpp"
#include "server/server.hpp"
#include "server/shutdown_signals.hpp"

namespace shadowtiles::cli {
namespace {

struct ServeFlags {
  std::string store, config_file, host;
  std::optional<int> port;
  std::optional<unsigned> threads;
  bool print_config = false;
};

int run(const ServeFlags& flags) {
  server::ServerConfig config;
  if (!flags.config_file.empty()) {
    auto loaded = server::ServerConfig::load(flags.config_file);
    if (!loaded) {
      spdlog::error("--config: {}", loaded.error().message);
      return kInvalidInput;
    }
    config = *loaded;
  }
  if (!flags.store.empty()) config.store = flags.store;
  if (config.store.empty() && !flags.print_config) {
    spdlog::error("serve: give the STORE directory (argument, or the config's \"store\" key)");
    return kInvalidInput;
  }
  if (!flags.host.empty()) config.host = flags.host;
  if (flags.port) config.port = *flags.port;
  if (flags.threads) config.threads = *flags.threads;
  if (Status s = config.validate(); !s) {
    spdlog::error("{}", s.error().message);
    return kInvalidInput;
  }
  if (flags.print_config) {
    std::cout << config.to_json().dump(2) << "\n";
    return kOk;
  }

  // Before any thread exists, so every server thread inherits the blocked signals.
  // The mutex keeps the watcher from calling stop() on a server being destroyed.
  std::mutex running_mutex;
  server::Server* running = nullptr;
  server::ShutdownSignals signals(
      [&](int) {
        std::lock_guard lock(running_mutex);
        if (running) running->stop();
      },
      [&] {
        std::lock_guard lock(running_mutex);
        if (!running) return;
        auto reloaded = running->reload();
        if (!reloaded) spdlog::warn("SIGHUP: keeping the current build: {}", reloaded.error().message);
        else if (!*reloaded) spdlog::info("SIGHUP: the store path still holds the served build");
        else spdlog::info("SIGHUP: reloaded, now serving the build the store path holds");
      });

  if (!server::keep_batch_buffers_resident()) spdlog::debug("allocator tuning not available: batch buffers are mapped per request");
  auto bound = server::Server::bind(config);
  if (!bound) {
    spdlog::error("{}", bound.error().message);
    return exit_code_for(bound.error());
  }
  server::Server& server = **bound;
  if (Status s = server.attach_store(config.store); !s) {
    // A build still being written (or incomplete) is served once done, if the path is polled.
    if (s.error().code != ErrorCode::invalid_input || config.reload_poll_s == 0) {
      spdlog::error("cannot open store: {}", s.error().message);
      return exit_code_for(s.error());
    }
    spdlog::warn("{}; answering 503 until it holds a complete build (checked every {} s)", s.error().message,
                 config.reload_poll_s);
  }
  {
    std::lock_guard lock(running_mutex);
    running = &server;
  }
  // The bound port is printed on stdout too, so scripts using --port 0 can read it.
  std::printf("listening on http://%s:%d\n", config.host.c_str(), server.port());
  std::fflush(stdout);
  spdlog::info("serving {} on http://{}:{} with {} threads", config.store, config.host, server.port(), config.threads);
  Status served = server.run();
  {
    std::lock_guard lock(running_mutex);
    running = nullptr;
  }
  if (!served) {
    spdlog::error("{}", served.error().message);
    return kFailure;
  }
  if (signals.received()) spdlog::info("stopped on signal {}; in-flight requests drained", signals.received());
  return kOk;
}

}  // namespace

void add_serve_command(CLI::App& app, int& exit_code) {
  auto flags = std::make_shared<ServeFlags>();
  CLI::App* cmd = app.add_subcommand("serve", "HTTP shadow service: point, batch and PCF queries, tile blobs");
  cmd->add_option("store", flags->store, "Store directory (default: the config's \"store\" key)");
  cmd->add_option("--config,-c", flags->config_file, "JSON config file (keys: config/README.md)");
  cmd->add_option("--host", flags->host, "Address to bind (default 127.0.0.1)");
  cmd->add_option("--port", flags->port, "Port (0: ephemeral, printed at start; default 8080)");
  cmd->add_option("--threads", flags->threads, "Worker threads (default 2)");
  cmd->add_flag("--print-config", flags->print_config, "Print the effective config as JSON and exit");
  cmd->callback([flags, &exit_code] { exit_code = run(*flags); });
}

}  // namespace shadowtiles::cli
