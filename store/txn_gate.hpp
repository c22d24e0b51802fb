// TxnGate: keeps LMDB transactions of this process out of the way while the memory map is replaced.
// mdb_env_set_mapsize munmaps and remaps the file, so it may only run when no transaction of this
// process is open (LMDB's rule). Every transaction holds the gate shared; a map resize holds it
// exclusively. Internal to store/.
//
// Policy: a pending exclusive request holds back new shared entries (so a busy reader pool cannot
// starve a resize), and waits at most a deadline for current holders to leave. On timeout it gives
// up and lets readers through again: a long-lived Snapshot can make a resize fail, never deadlock.
// Thread safety: all members may be called from any thread.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <mutex>

namespace shadowtiles::store::detail {

class TxnGate {
 public:
  // Blocks while an exclusive section is pending or running (bounded by that section's deadline).
  void enter_shared();
  void leave_shared();
  // True once no shared holders remain; false if that did not happen within `wait`.
  bool enter_exclusive(std::chrono::milliseconds wait);
  void leave_exclusive();
  size_t shared_count() const;

 private:
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  size_t shared_ = 0;
  bool exclusive_ = false;  // requested or held
};

}  // namespace shadowtiles::store::detail
