// RenderPool: the inspector's own threads for /v1/render (issue 17), apart from the HTTP workers
// and the batch-query pool, so drawing map tiles never runs on the threads that answer queries. A
// fixed number of threads and a bounded queue: a job beyond the queue is refused at once (the
// route answers 503 with Retry-After) instead of piling up.
// Thread safety: try_submit may be called from any thread. The destructor drains queued jobs
// (each runs) and joins the threads.
#pragma once

#include <algorithm>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace shadowtiles::server {

class RenderPool {
 public:
  RenderPool(unsigned threads, size_t queue_capacity);
  ~RenderPool();
  RenderPool(const RenderPool&) = delete;
  RenderPool& operator=(const RenderPool&) = delete;

  // False when the queue is full (the job is not taken). `job` must not throw.
  bool try_submit(std::function<void()> job);

 private:
  void loop();
  const size_t capacity_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::function<void()>> jobs_;
  bool stopping_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace shadowtiles::server
