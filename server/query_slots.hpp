// QuerySlots: the `threads` query workers, as slots a handler holds while it computes. Connection
// I/O (reading requests, writing answers) runs on I/O threads outside any slot, so slow clients
// never hold query capacity; at most `threads` requests decode and answer at once, and a request
// waits at most `wait` for a slot before it is answered 503 busy (never an unbounded queue).
// Waiters queue first come, first served and a release wakes only the longest waiter (libstdc++
// 12's std::counting_semaphore wakes every waiter on each release: with 64 connections on 2 cores,
// a herd of threads that mostly go back to sleep). A request that arrives while a slot is free
// takes it at once, even past a waiter that was woken but not yet scheduled: handing the slot to
// the sleeping waiter instead would leave it idle for a wake-up latency on every release (a convoy,
// measured at 4x the p99 of point GETs on a loaded 2-core machine). A waiter passed over stays first
// in line and is woken again by the next release; query_wait_ms bounds its wait.
// Thread safety: acquire() may be called concurrently; a Slot releases on destruction.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <mutex>

namespace shadowtiles::server {

class QuerySlots {
 public:
  explicit QuerySlots(unsigned slots) : free_(slots) {}

  class Slot {
   public:
    Slot() = default;
    explicit Slot(QuerySlots* owner) : owner_(owner) {}
    Slot(Slot&& other) noexcept : owner_(other.owner_) { other.owner_ = nullptr; }
    Slot& operator=(Slot&&) = delete;
    ~Slot() {
      if (owner_) owner_->release();
    }
    explicit operator bool() const { return owner_ != nullptr; }

   private:
    QuerySlots* owner_ = nullptr;
  };

  // An empty Slot when none is free for this request within `wait`.
  Slot acquire(std::chrono::milliseconds wait);

  // Requests waiting for a slot now (for tests and metrics).
  size_t waiting() const;

 private:
  struct Waiter {
    std::condition_variable wake;
  };
  void release();

  mutable std::mutex mutex_;
  unsigned free_;
  std::deque<Waiter*> waiters_;  // oldest first; each lives on its waiting thread's stack
};

}  // namespace shadowtiles::server
