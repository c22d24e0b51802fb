#include "server/query_slots.hpp"

#include <algorithm>

namespace shadowtiles::server {

QuerySlots::Slot QuerySlots::acquire(std::chrono::milliseconds wait) {
  std::unique_lock lock(mutex_);
  if (free_ > 0) {
    --free_;
    return Slot(this);
  }
  Waiter me;
  waiters_.push_back(&me);
  // Only the first in line takes a freed slot (a spurious wake-up further back does not).
  const bool got = me.wake.wait_for(lock, wait, [&] { return free_ > 0 && waiters_.front() == &me; });
  waiters_.erase(std::find(waiters_.begin(), waiters_.end(), &me));
  if (got) --free_;
  // A slot still free (released while this waiter was leaving, or more than one freed) goes on.
  if (free_ > 0 && !waiters_.empty()) waiters_.front()->wake.notify_one();
  return got ? Slot(this) : Slot();
}

void QuerySlots::release() {
  std::lock_guard lock(mutex_);
  ++free_;
  if (!waiters_.empty()) waiters_.front()->wake.notify_one();
}

size_t QuerySlots::waiting() const {
  std::lock_guard lock(mutex_);
  return waiters_.size();
}

}  // namespace shadowtiles::server
