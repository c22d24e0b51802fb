// Lookup rate: how many shadow queries per second a ShadowMap answers through its public API
// (world point -> light space -> cached tile -> decoded value), for point queries (kernel 1) or
// PCF k x k, over a fixed list of points visited in the given order, on 1..n threads.
// Method: one untimed warm-up pass over all points (so their tiles are decoded and cached), then
// every thread walks the list cyclically (thread i starting at i/n of it, so each keeps the order's
// coherence) for a round of wall time; rate = the best round's lookups / its wall time.
// Interleaved rounds (InterleavedRates): the measurements a report divides by one another (1 and 2
// threads, point and PCF, a method and raw, the store and Embree) run one round each in turn, round
// after round, so they share the same stretch of wall time. On this shared machine a neighbour's
// burst that lasts seconds slowed every round of one measurement when each ran its rounds back to
// back (the same 1-thread MH cell read 8.1 and 2.5 M/s in two runs of unchanged code); interleaved,
// it slows one round of each and the best round of each is the code's own speed.
// Cache misses during the timed rounds are reported: non-zero means the cache budget is too small
// for the points' tiles and the rate includes decoding.
// Errors: the first query error (corrupt tile, unknown method).
// Thread safety: the ShadowMap is shared by the threads (its cache is locked: this is measured too).
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "client/shadow_map.hpp"

namespace shadowtiles::bench {

struct LookupRate {
  double lookups_per_second = 0;  // the best round's
  uint64_t lookups = 0;           // over every round
  double seconds = 0;             // over every round
  uint64_t cache_misses = 0;      // during the timed rounds
};

class InterleavedRates {
 public:
  // One timed round of a measurement, of about `seconds` of wall time.
  using Round = std::function<Result<LookupRate>(double seconds)>;
  static constexpr unsigned kDefaultRounds = 5;

  // Returns the measurement's index in run()'s result.
  size_t add(Round round) {
    rounds_.push_back(std::move(round));
    return rounds_.size() - 1;
  }
  size_t size() const { return rounds_.size(); }
  // `rounds` rounds; in each, every measurement in the order added, for min_seconds / rounds each
  // (so each measurement runs about min_seconds in all, as if it were alone).
  // Errors: the first round's error.
  Result<std::vector<LookupRate>> run(double min_seconds, unsigned rounds = kDefaultRounds) const;

 private:
  std::vector<Round> rounds_;
};

// Rounds of ShadowMap::query (kernel 1) or query_pcf (kernel k) over `points`; warms up when called.
// `map` and `points` must outlive the rounds. `kernel` 1 = point query, else PCF kernel side (odd).
Result<InterleavedRates::Round> lookup_rounds(const ShadowMap& map, store::Method method,
                                              std::span<const Vec3> points, unsigned kernel, unsigned threads);

// The same loop for any per-point answer (the Embree occlusion-ray peer): `look_up` returns 0 or 1.
InterleavedRates::Round point_rounds(std::span<const Vec3> points, unsigned threads,
                                     std::function<double(const Vec3&)> look_up);

// ShadowMap::query_batch over all `points` at once (after one untimed warm-up batch, when called):
// a round repeats it until its time passed (at least once); rate = the best batch's points / its
// wall time.
Result<InterleavedRates::Round> batch_rounds(const ShadowMap& map, store::Method method,
                                             std::span<const Vec3> points, unsigned kernel, unsigned threads);

// Latency of single point queries, one at a time on one thread (warm): p50 and p99 in microseconds.
struct Latency {
  double p50_us = 0, p99_us = 0;
};
Result<Latency> measure_point_latency(const ShadowMap& map, store::Method method, std::span<const Vec3> points);

}  // namespace shadowtiles::bench
