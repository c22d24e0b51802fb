// BatchPool: splits one large batch of point queries across a fixed, small set of threads (the
// configured worker count), so a 100k-point request uses every core without spawning threads per
// request. The calling thread runs one share itself; `width - 1` helper threads run the rest.
// Bounded: at most `width - 1` helpers exist for the pool's lifetime; concurrent batches queue.
// Thread safety: parallel_for may be called concurrently from any thread. The destructor joins the
// helpers and must not run while a parallel_for is in progress.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace shadowtiles::server {

class BatchPool {
 public:
  explicit BatchPool(unsigned width);
  ~BatchPool();
  BatchPool(const BatchPool&) = delete;
  BatchPool& operator=(const BatchPool&) = delete;

  unsigned width() const { return width_; }
  // Calls fn(begin, end) on disjoint ranges covering [0, count), in at most width() chunks of at
  // least `min_chunk` items, and returns when all have finished. `fn` must not throw.
  void parallel_for(size_t count, size_t min_chunk, const std::function<void(size_t, size_t)>& fn);

 private:
  void helper_loop();

  unsigned width_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::function<void()>> jobs_;
  bool stopping_ = false;
  std::vector<std::thread> helpers_;
};

}  // namespace shadowtiles::server
