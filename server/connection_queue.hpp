// ConnectionQueue: the connection task queue handed to cpp-httplib (Server::new_task_queue), which
// in v0.11 has no connection limit of its own. `workers` threads serve connections; at most
// `max_connections` connections are being served or waiting for a worker. A connection beyond that
// goes to one shedding thread instead, whose requests are answered 503 at once (the pre-routing
// hook asks shedding()), so a flood cannot queue unbounded work behind the workers. The shedding
// thread reads request headers under the configured read timeout, so a slow client holds it at
// most that long.
// shutdown() (called by httplib after stop()) finishes every connection already accepted: in-flight
// requests drain.
// Thread safety: enqueue/shutdown are called by httplib's accept loop; shedding() by any thread.
#pragma once

#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include <httplib.h>

namespace shadowtiles::server {

class ConnectionQueue : public httplib::TaskQueue {
 public:
  ConnectionQueue(unsigned workers, unsigned max_connections);
  ~ConnectionQueue() override;

  void enqueue(std::function<void()> fn) override;
  void shutdown() override;

  // True on the shedding thread: the connection it serves is over the limit.
  static bool shedding();

 private:
  struct Lane {
    std::deque<std::function<void()>> jobs;
    std::condition_variable wake;
  };
  void run(Lane& lane, bool shed);

  const unsigned max_connections_;
  std::mutex mutex_;
  Lane serve_, shed_;
  unsigned active_ = 0;  // connections queued or being served on serve_
  bool stopping_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace shadowtiles::server
