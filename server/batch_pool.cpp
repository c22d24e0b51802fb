#include "server/batch_pool.hpp"

#include <algorithm>
#include <latch>

namespace shadowtiles::server {

BatchPool::BatchPool(unsigned width) : width_(std::max(1u, width)) {
  for (unsigned i = 1; i < width_; ++i) helpers_.emplace_back([this] { helper_loop(); });
}

BatchPool::~BatchPool() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  for (std::thread& t : helpers_) t.join();
}

void BatchPool::helper_loop() {
  for (;;) {
    std::function<void()> job;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [&] { return stopping_ || !jobs_.empty(); });
      if (jobs_.empty()) return;  // stopping and drained
      job = std::move(jobs_.front());
      jobs_.pop_front();
    }
    job();
  }
}

void BatchPool::parallel_for(size_t count, size_t min_chunk, const std::function<void(size_t, size_t)>& fn) {
  if (count == 0) return;
  size_t chunks = std::min<size_t>(width_, std::max<size_t>(1, count / std::max<size_t>(1, min_chunk)));
  if (chunks <= 1) {
    fn(0, count);
    return;
  }
  const size_t step = (count + chunks - 1) / chunks;
  chunks = (count + step - 1) / step;
  std::latch done(ptrdiff_t(chunks - 1));
  {
    std::lock_guard lock(mutex_);
    for (size_t c = 1; c < chunks; ++c) {
      size_t begin = c * step, end = std::min(count, begin + step);
      jobs_.push_back([&fn, &done, begin, end] {
        fn(begin, end);
        done.count_down();
      });
    }
  }
  wake_.notify_all();
  fn(0, std::min(count, step));
  // Help with queued chunks (ours or another batch's) rather than sleep: no deadlock even when all
  // helpers are busy, and the caller's core stays in use.
  for (;;) {
    if (done.try_wait()) break;
    std::function<void()> job;
    {
      std::lock_guard lock(mutex_);
      if (!jobs_.empty()) {
        job = std::move(jobs_.front());
        jobs_.pop_front();
      }
    }
    if (job) job();
    else {
      done.wait();
      break;
    }
  }
}

}  // namespace shadowtiles::server
