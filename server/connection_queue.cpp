#include "server/connection_queue.hpp"

namespace shadowtiles::server {
namespace {
thread_local bool t_shedding = false;
}

bool ConnectionQueue::shedding() { return t_shedding; }

ConnectionQueue::ConnectionQueue(unsigned workers, unsigned max_connections) : max_connections_(max_connections) {
  for (unsigned i = 0; i < workers; ++i) threads_.emplace_back([this] { run(serve_, false); });
  threads_.emplace_back([this] { run(shed_, true); });
}

ConnectionQueue::~ConnectionQueue() { shutdown(); }

void ConnectionQueue::enqueue(std::function<void()> fn) {
  {
    std::lock_guard lock(mutex_);
    if (active_ < max_connections_) {
      ++active_;
      serve_.jobs.push_back(std::move(fn));
      serve_.wake.notify_one();
      return;
    }
    shed_.jobs.push_back(std::move(fn));
  }
  shed_.wake.notify_one();
}

void ConnectionQueue::shutdown() {
  {
    std::lock_guard lock(mutex_);
    if (stopping_ && threads_.empty()) return;
    stopping_ = true;
  }
  serve_.wake.notify_all();
  shed_.wake.notify_all();
  for (std::thread& t : threads_) t.join();
  threads_.clear();
}

void ConnectionQueue::run(Lane& lane, bool shed) {
  t_shedding = shed;
  for (;;) {
    std::function<void()> job;
    {
      std::unique_lock lock(mutex_);
      lane.wake.wait(lock, [&] { return stopping_ || !lane.jobs.empty(); });
      if (lane.jobs.empty()) return;  // stopping and drained
      job = std::move(lane.jobs.front());
      lane.jobs.pop_front();
    }
    job();  // httplib's job serves the connection and closes its socket
    if (!shed) {
      std::lock_guard lock(mutex_);
      --active_;
    }
  }
}

}  // namespace shadowtiles::server
