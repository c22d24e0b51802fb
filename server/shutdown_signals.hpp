// ShutdownSignals: turns SIGTERM / SIGINT into a clean stop (docs/architecture.md §10: drain, exit 0), and
// SIGHUP into a reload (docs/architecture.md §9: swap to a new build) when `on_reload` is given.
// Construct it before any other thread starts: it blocks both signals in the calling thread, so
// every thread created afterwards inherits the mask, and one watcher thread receives them with
// sigtimedwait and calls `on_signal` (from that ordinary thread, so on_signal may lock, log and call
// Server::stop()). on_signal is called again every 100 ms until the object is destroyed, so a stop
// that raced with the server's start is repeated. The destructor ends the watcher and restores the
// previous signal mask of the constructing thread.
// Thread safety: one instance per process; construct and destroy on the same thread.
#pragma once

#include <atomic>
#include <csignal>
#include <functional>
#include <thread>

namespace shadowtiles::server {

class ShutdownSignals {
 public:
  explicit ShutdownSignals(std::function<void(int signal)> on_signal, std::function<void()> on_reload = {});
  ~ShutdownSignals();
  ShutdownSignals(const ShutdownSignals&) = delete;
  ShutdownSignals& operator=(const ShutdownSignals&) = delete;

  int received() const { return received_.load(); }  // 0: none yet

 private:
  std::function<void(int)> on_signal_;
  std::function<void()> on_reload_;
  sigset_t previous_{};
  std::atomic<bool> done_{false};
  std::atomic<int> received_{0};
  std::thread watcher_;
};

}  // namespace shadowtiles::server
