#include "server/connection_queue.hpp"

namespace shadowtiles::server {
namespace {
thread_local ConnectionQueue::Lane t_lane = ConnectionQueue::Lane::io;
}

ConnectionQueue::Lane ConnectionQueue::lane() { return t_lane; }

ConnectionQueue::ConnectionQueue(unsigned max_connections) : max_connections_(max_connections) {
  shed_thread_ = std::thread([this] { shed_loop(); });
}

ConnectionQueue::~ConnectionQueue() { shutdown(); }

void ConnectionQueue::start_io(std::unique_lock<std::mutex>& lock, std::function<void()> fn) {
  ++active_;
  io_jobs_.push_back(std::move(fn));
  // An idle thread takes it; otherwise start one (never more than max_connections threads).
  if (idle_io_ >= io_jobs_.size() || io_threads_.size() >= max_connections_) {
    lock.unlock();
    io_wake_.notify_one();
  } else {
    io_threads_.emplace_back([this] { io_loop(); });
    lock.unlock();
  }
}

void ConnectionQueue::enqueue(std::function<void()> fn) {
  std::unique_lock lock(mutex_);
  if (active_ < max_connections_ && shed_jobs_.empty()) return start_io(lock, std::move(fn));
  shed_jobs_.push_back({std::move(fn), shed_jobs_.size() < kMaxShedBacklog ? Lane::shed : Lane::drop});
  lock.unlock();
  shed_wake_.notify_one();
}

void ConnectionQueue::shutdown() {
  std::vector<std::thread> threads;
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    threads.swap(io_threads_);
  }
  io_wake_.notify_all();
  shed_wake_.notify_all();
  for (std::thread& t : threads) t.join();
  if (shed_thread_.joinable()) shed_thread_.join();
}

void ConnectionQueue::io_loop() {
  t_lane = Lane::io;
  std::unique_lock lock(mutex_);
  for (;;) {
    ++idle_io_;
    io_wake_.wait(lock, [&] { return stopping_ || !io_jobs_.empty(); });
    --idle_io_;
    if (io_jobs_.empty()) return;  // stopping and drained
    std::function<void()> job = std::move(io_jobs_.front());
    io_jobs_.pop_front();
    lock.unlock();
    job();  // httplib's job serves the connection and closes its socket
    job = nullptr;
    lock.lock();
    --active_;
    slot_freed_.notify_one();
  }
}

void ConnectionQueue::shed_loop() {
  std::unique_lock lock(mutex_);
  for (;;) {
    shed_wake_.wait(lock, [&] { return stopping_ || !shed_jobs_.empty(); });
    if (shed_jobs_.empty()) return;
    Job job = std::move(shed_jobs_.front());
    shed_jobs_.pop_front();
    // The grace only when no flood is queued behind: a backlog is answered 503 without waiting.
    if (job.lane == Lane::shed && shed_jobs_.empty() &&
        slot_freed_.wait_for(lock, kShedGrace, [&] { return stopping_ || active_ < max_connections_; }) &&
        !stopping_) {
      start_io(lock, std::move(job.fn));
      lock.lock();
      continue;
    }
    lock.unlock();
    t_lane = job.lane;
    job.fn();
    job.fn = nullptr;
    lock.lock();
  }
}

}  // namespace shadowtiles::server
