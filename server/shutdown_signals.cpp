#include "server/shutdown_signals.hpp"

#include <pthread.h>

#include <ctime>

namespace shadowtiles::server {

ShutdownSignals::ShutdownSignals(std::function<void(int)> on_signal, std::function<void()> on_reload)
    : on_signal_(std::move(on_signal)), on_reload_(std::move(on_reload)) {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  if (on_reload_) sigaddset(&set, SIGHUP);
  pthread_sigmask(SIG_BLOCK, &set, &previous_);
  watcher_ = std::thread([this, set] {
    const timespec tick{0, 100'000'000};
    while (!done_.load()) {
      int signal = sigtimedwait(&set, nullptr, &tick);
      if (signal == SIGHUP) {
        on_reload_();
        continue;
      }
      if (signal > 0 && received_.load() == 0) received_.store(signal);
      if (received_.load() != 0) on_signal_(received_.load());
    }
  });
}

ShutdownSignals::~ShutdownSignals() {
  done_.store(true);
  watcher_.join();
  pthread_sigmask(SIG_SETMASK, &previous_, nullptr);
}

}  // namespace shadowtiles::server
