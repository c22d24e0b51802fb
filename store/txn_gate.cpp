#include "store/txn_gate.hpp"

#include <cassert>

namespace shadowtiles::store::detail {

void TxnGate::enter_shared() {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [&] { return !exclusive_; });
  ++shared_;
}

void TxnGate::leave_shared() {
  std::lock_guard lock(mutex_);
  assert(shared_ > 0);
  if (--shared_ == 0) changed_.notify_all();
}

bool TxnGate::enter_exclusive(std::chrono::milliseconds wait) {
  const auto deadline = std::chrono::steady_clock::now() + wait;
  std::unique_lock lock(mutex_);
  // One exclusive section at a time.
  if (!changed_.wait_until(lock, deadline, [&] { return !exclusive_; })) return false;
  exclusive_ = true;
  if (!changed_.wait_until(lock, deadline, [&] { return shared_ == 0; })) {
    exclusive_ = false;
    changed_.notify_all();
    return false;
  }
  return true;
}

void TxnGate::leave_exclusive() {
  std::lock_guard lock(mutex_);
  assert(exclusive_);
  exclusive_ = false;
  changed_.notify_all();
}

size_t TxnGate::shared_count() const {
  std::lock_guard lock(mutex_);
  return shared_;
}

}  // namespace shadowtiles::store::detail
