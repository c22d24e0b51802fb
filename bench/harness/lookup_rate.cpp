#include "bench/harness/lookup_rate.hpp"

#include <atomic>
#include <chrono>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

namespace shadowtiles::bench {
namespace {

using Clock = std::chrono::steady_clock;

// One query; returns a value the caller accumulates so the compiler cannot drop the call.
Result<double> look_up(const ShadowMap& map, store::Method method, const Vec3& point, unsigned kernel) {
  if (kernel == 1) {
    auto answer = map.query(point, method);
    if (!answer) return answer.error();
    return answer->lit ? 1.0 : 0.0;
  }
  return map.query_pcf(point, method, kernel);
}

}  // namespace

Result<LookupRate> measure_lookup_rate(const ShadowMap& map, store::Method method, std::span<const Vec3> points,
                                       unsigned kernel, unsigned threads, double min_seconds) {
  LookupRate rate;
  if (points.empty() || threads == 0) return rate;
  double sink = 0;
  for (const Vec3& p : points) {  // warm-up: decode and cache the tiles
    auto value = look_up(map, method, p, kernel);
    if (!value) return value.error();
    sink += *value;
  }
  const uint64_t misses_before = map.cache_stats().misses;
  std::atomic<uint64_t> total{0};
  std::mutex error_mutex;
  std::optional<Error> error;
  std::atomic<bool> failed{false};
  const auto start = Clock::now();
  const auto deadline = start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(min_seconds));
  auto worker = [&](unsigned index) {
    size_t i = points.size() * index / threads;
    uint64_t count = 0;
    double local_sink = 0;
    // Check the clock every 64 lookups: cheap next to a lookup, fine-grained enough for 0.3 s.
    do {
      for (int j = 0; j < 64; ++j, ++count) {
        auto value = look_up(map, method, points[i], kernel);
        if (!value) {
          std::lock_guard lock(error_mutex);
          if (!error) error = value.error();
          failed = true;
          return;
        }
        local_sink += *value;
        if (++i == points.size()) i = 0;
      }
    } while (Clock::now() < deadline && !failed);
    total += count;
    if (local_sink < 0) std::abort();            // never: a use of the result the optimiser must keep
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < threads; ++t) pool.emplace_back(worker, t);
  worker(0);
  for (auto& t : pool) t.join();
  if (error) return *error;
  rate.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  rate.lookups = total;
  rate.lookups_per_second = rate.seconds > 0 ? double(rate.lookups) / rate.seconds : 0;
  rate.cache_misses = map.cache_stats().misses - misses_before;
  if (sink < 0) std::abort();
  return rate;
}

}  // namespace shadowtiles::bench
