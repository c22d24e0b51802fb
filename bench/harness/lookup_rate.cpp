#include "bench/harness/lookup_rate.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <type_traits>
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

// The timed part of the rate measurements: every thread walks `points` cyclically (thread i from
// i/n of it) until `min_seconds` passed; returns the lookups made, the wall time and their rate.
// `look_up(point)` returns the answer as a number, or (when it can fail) a Result of one; the first
// error stops every thread and is returned.
template <typename LookUp>
Result<LookupRate> timed_cyclic_lookups(std::span<const Vec3> points, unsigned threads, double min_seconds,
                                        const LookUp& look_up) {
  constexpr bool can_fail = !std::is_arithmetic_v<std::invoke_result_t<const LookUp&, const Vec3&>>;
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
        if constexpr (can_fail) {
          auto value = look_up(points[i]);
          if (!value) {
            std::lock_guard lock(error_mutex);
            if (!error) error = value.error();
            failed = true;
            return;
          }
          local_sink += *value;
        } else {
          local_sink += look_up(points[i]);
        }
        if (++i == points.size()) i = 0;
      }
    } while (Clock::now() < deadline && !failed);
    total += count;
    if (local_sink < 0) std::abort();  // never: a use of the result the optimiser must keep
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < threads; ++t) pool.emplace_back(worker, t);
  worker(0);
  for (auto& t : pool) t.join();
  if (error) return *error;
  LookupRate rate;
  rate.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  rate.lookups = total;
  rate.lookups_per_second = rate.seconds > 0 ? double(rate.lookups) / rate.seconds : 0;
  return rate;
}

}  // namespace

Result<std::vector<LookupRate>> InterleavedRates::run(double min_seconds, unsigned rounds) const {
  rounds = std::max(1u, rounds);
  std::vector<LookupRate> best(rounds_.size());
  std::vector<LookupRate> total(rounds_.size());
  for (unsigned round = 0; round < rounds; ++round) {
    for (size_t i = 0; i < rounds_.size(); ++i) {
      Result<LookupRate> rate = rounds_[i](min_seconds / rounds);
      if (!rate) return rate.error();
      total[i].lookups += rate->lookups;
      total[i].seconds += rate->seconds;
      total[i].cache_misses += rate->cache_misses;
      best[i].lookups_per_second = std::max(best[i].lookups_per_second, rate->lookups_per_second);
    }
  }
  for (size_t i = 0; i < rounds_.size(); ++i) total[i].lookups_per_second = best[i].lookups_per_second;
  return total;
}

Result<InterleavedRates::Round> lookup_rounds(const ShadowMap& map, store::Method method,
                                              std::span<const Vec3> points, unsigned kernel, unsigned threads) {
  if (threads == 0) return make_error(ErrorCode::invalid_input, "lookup rounds need at least one thread");
  double sink = 0;
  for (const Vec3& p : points) {  // warm-up: decode and cache the tiles
    auto value = look_up(map, method, p, kernel);
    if (!value) return value.error();
    sink += *value;
  }
  if (sink < 0) std::abort();
  return InterleavedRates::Round([&map, method, points, kernel, threads](double seconds) -> Result<LookupRate> {
    if (points.empty()) return LookupRate{};
    const uint64_t misses_before = map.cache_stats().misses;
    auto rate = timed_cyclic_lookups(points, threads, seconds,
                                     [&](const Vec3& p) { return look_up(map, method, p, kernel); });
    if (!rate) return rate.error();
    rate->cache_misses = map.cache_stats().misses - misses_before;
    return rate;
  });
}

InterleavedRates::Round point_rounds(std::span<const Vec3> points, unsigned threads,
                                     std::function<double(const Vec3&)> look_up) {
  double sink = 0;
  for (const Vec3& p : points) sink += look_up(p);  // warm-up
  if (sink < 0) std::abort();
  return [points, threads, look_up = std::move(look_up)](double seconds) -> Result<LookupRate> {
    if (points.empty() || threads == 0) return LookupRate{};
    return timed_cyclic_lookups(points, threads, seconds, look_up);  // look_up cannot fail
  };
}

Result<InterleavedRates::Round> batch_rounds(const ShadowMap& map, store::Method method,
                                             std::span<const Vec3> points, unsigned kernel, unsigned threads) {
  ShadowMap::BatchOptions options;
  options.kernel = kernel;
  options.threads = threads;
  // Shared by the copies of the round (std::function copies): the batch's buffers, kept between
  // batches as a caller would keep them.
  auto answers = std::make_shared<ShadowMap::BatchAnswers>();
  if (!points.empty())
    if (Status s = map.query_batch(points, method, options, *answers); !s) return s.error();  // warm-up
  return InterleavedRates::Round([&map, method, points, options, answers](double seconds) -> Result<LookupRate> {
    LookupRate rate;
    if (points.empty()) return rate;
    const uint64_t misses_before = map.cache_stats().misses;
    const auto start = Clock::now();
    do {  // the round's rate is its best batch's
      const auto batch_start = Clock::now();
      if (Status s = map.query_batch(points, method, options, *answers); !s) return s.error();
      const double batch_seconds = std::chrono::duration<double>(Clock::now() - batch_start).count();
      if (batch_seconds > 0)
        rate.lookups_per_second = std::max(rate.lookups_per_second, double(points.size()) / batch_seconds);
      rate.lookups += points.size();
      rate.seconds = std::chrono::duration<double>(Clock::now() - start).count();
    } while (rate.seconds < seconds);
    rate.cache_misses = map.cache_stats().misses - misses_before;
    return rate;
  });
}

Result<Latency> measure_point_latency(const ShadowMap& map, store::Method method, std::span<const Vec3> points) {
  Latency latency;
  if (points.empty()) return latency;
  for (const Vec3& p : points)  // warm
    if (auto a = map.query(p, method); !a) return a.error();
  std::vector<double> us;
  us.reserve(points.size());
  for (const Vec3& p : points) {
    const auto t0 = Clock::now();
    auto a = map.query(p, method);
    const auto t1 = Clock::now();
    if (!a) return a.error();
    us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
  }
  std::sort(us.begin(), us.end());
  latency.p50_us = us[us.size() / 2];
  latency.p99_us = us[std::min(us.size() - 1, us.size() * 99 / 100)];
  return latency;
}

}  // namespace shadowtiles::bench
