// ConnectionQueue: the connection task queue handed to cpp-httplib (Server::new_task_queue), which
// in v0.11 has no connection limit of its own. Each accepted connection is one job:
//   - up to `max_connections` connections run at once, each on its own I/O thread (threads are
//     started on demand and kept, so at most max_connections exist). An I/O thread only moves
//     bytes and parses; query work runs under a query slot (QuerySlots), so slow or idle clients
//     hold I/O threads, never the capacity that answers queries;
//   - a connection beyond that goes to one shedding thread. It waits up to kShedGrace for a slot
//     (a keep-alive client that just reconnected often races its own old connection's close) and
//     then either serves it on an I/O thread or answers 503 at once without reading the request
//     (lane() == shed: HttpService, shed_connection);
//   - beyond kMaxShedBacklog waiting on the shedding thread, connections are closed unanswered
//     (lane() == drop), so a flood cannot queue unbounded work.
// shutdown() (called by httplib after stop()) finishes every connection already accepted: in-flight
// requests drain.
// Thread safety: enqueue/shutdown are called by httplib's accept loop; lane() by any thread.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include <httplib.h>

namespace shadowtiles::server {

class ConnectionQueue : public httplib::TaskQueue {
 public:
  enum class Lane { io, shed, drop };
  static constexpr size_t kMaxShedBacklog = 256;
  static constexpr std::chrono::milliseconds kShedGrace{50};

  explicit ConnectionQueue(unsigned max_connections);
  ~ConnectionQueue() override;

  void enqueue(std::function<void()> fn) override;
  void shutdown() override;

  // The lane of the connection the calling thread serves.
  static Lane lane();

 private:
  struct Job {
    std::function<void()> fn;
    Lane lane;
  };
  void io_loop();
  void shed_loop();
  // Queues `fn` for an I/O thread (starting one when none is idle). Called with `lock` held on
  // mutex_; returns with it released.
  void start_io(std::unique_lock<std::mutex>& lock, std::function<void()> fn);

  const unsigned max_connections_;
  std::mutex mutex_;
  std::condition_variable io_wake_, shed_wake_, slot_freed_;
  std::deque<std::function<void()>> io_jobs_;
  std::deque<Job> shed_jobs_;
  unsigned active_ = 0;    // connections queued for or running on I/O threads
  unsigned idle_io_ = 0;   // I/O threads waiting for a job
  bool stopping_ = false;
  std::vector<std::thread> io_threads_;
  std::thread shed_thread_;
};

}  // namespace shadowtiles::server
