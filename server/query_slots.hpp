// QuerySlots: the `threads` query workers, as slots a handler holds while it computes. Connection
// I/O (reading requests, writing answers) runs on I/O threads outside any slot, so slow clients
// never hold query capacity; at most `threads` requests decode and answer at once, and a request
// waits at most `wait` for a slot before it is answered 503 busy (never an unbounded queue).
// Thread safety: acquire() may be called concurrently; a Slot releases on destruction.
#pragma once

#include <chrono>
#include <cstddef>
#include <semaphore>

namespace shadowtiles::server {

class QuerySlots {
 public:
  explicit QuerySlots(unsigned slots) : free_(std::ptrdiff_t(slots)) {}

  class Slot {
   public:
    Slot() = default;
    explicit Slot(std::counting_semaphore<>* owner) : owner_(owner) {}
    Slot(Slot&& other) noexcept : owner_(other.owner_) { other.owner_ = nullptr; }
    Slot& operator=(Slot&&) = delete;
    ~Slot() {
      if (owner_) owner_->release();
    }
    explicit operator bool() const { return owner_ != nullptr; }

   private:
    std::counting_semaphore<>* owner_ = nullptr;
  };

  // An empty Slot when none frees up within `wait`.
  Slot acquire(std::chrono::milliseconds wait) {
    if (free_.try_acquire() || free_.try_acquire_for(wait)) return Slot(&free_);
    return Slot();
  }

 private:
  std::counting_semaphore<> free_;
};

}  // namespace shadowtiles::server
