// Lookup rate: how many shadow queries per second a ShadowMap answers through its public API
// (world point -> light space -> cached tile -> decoded value), for point queries (kernel 1) or
// PCF k x k, over a fixed list of points visited in the given order, on 1..n threads.
// Method: one untimed warm-up pass over all points (so their tiles are decoded and cached), then
// every thread walks the list cyclically (thread i starting at i/n of it, so each keeps the order's
// coherence) for 5 rounds of `min_seconds` / 5 of wall time each; rate = the best round's lookups /
// its wall time (a shared machine's bursts slow some rounds; lookup_rate.cpp, best_of_rounds).
// Cache misses during the timed loops are reported: non-zero means the cache budget is too small
// for the points' tiles and the rate includes decoding.
// Errors: the first query error (corrupt tile, unknown method).
// Thread safety: the ShadowMap is shared by the threads (its cache is locked: this is measured too).
#pragma once

#include <cstdint>
#include <functional>
#include <span>

#include "client/shadow_map.hpp"

namespace shadowtiles::bench {

struct LookupRate {
  double lookups_per_second = 0;
  uint64_t lookups = 0;
  double seconds = 0;
  uint64_t cache_misses = 0;  // during the timed loops
};

// `kernel` 1 = point query, else PCF kernel side (odd).
Result<LookupRate> measure_lookup_rate(const ShadowMap& map, store::Method method, std::span<const Vec3> points,
                                       unsigned kernel, unsigned threads, double min_seconds);

// The same loop for any per-point answer (the Embree occlusion-ray peer): `look_up` returns 0 or 1.
LookupRate measure_point_rate(std::span<const Vec3> points, unsigned threads, double min_seconds,
                              const std::function<double(const Vec3&)>& look_up);

// ShadowMap::query_batch over all `points` at once, repeated until `min_seconds` passed and at least
// 3 times (after one untimed warm-up batch); rate = the best batch's points / its wall time.
Result<LookupRate> measure_batch_rate(const ShadowMap& map, store::Method method, std::span<const Vec3> points,
                                      unsigned kernel, unsigned threads, double min_seconds);

// Latency of single point queries, one at a time on one thread (warm): p50 and p99 in microseconds.
struct Latency {
  double p50_us = 0, p99_us = 0;
};
Result<Latency> measure_point_latency(const ShadowMap& map, store::Method method, std::span<const Vec3> points);

}  // namespace shadowtiles::bench
