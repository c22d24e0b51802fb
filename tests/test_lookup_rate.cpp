// InterleavedRates (bench/harness/lookup_rate.hpp): the measurements a report divides by one another
// take one round each in turn, so a disturbance of the machine lands on a round of each, and every
// cell is its best round. Checked with scripted rounds (no timing): the call order, the best round,
// the totals, the per-round time budget, and that a failing round stops the run with its error.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "bench/harness/lookup_rate.hpp"

namespace st = shadowtiles;
using st::bench::InterleavedRates;
using st::bench::LookupRate;

namespace {

// A round that records its call and answers the next of `rates` (lookups/s; 1 s, 1 lookup per unit).
InterleavedRates::Round scripted(int id, std::vector<double> rates, std::vector<std::pair<int, double>>& calls) {
  auto next = std::make_shared<size_t>(0);
  return [id, rates, next, &calls](double seconds) -> st::Result<LookupRate> {
    calls.push_back({id, seconds});
    LookupRate rate;
    rate.lookups_per_second = rates.at((*next)++);
    rate.lookups = uint64_t(rate.lookups_per_second);
    rate.seconds = 1;
    rate.cache_misses = 1;
    return rate;
  };
}

}  // namespace

TEST(InterleavedRates, RunsOneRoundOfEachInTurnAndKeepsEachBestRound) {
  std::vector<std::pair<int, double>> calls;
  InterleavedRates rates;
  // Measurement 0 is disturbed in its first three rounds, measurement 1 in its last two: run back to
  // back, one of them would have been disturbed throughout.
  EXPECT_EQ(rates.add(scripted(0, {10, 11, 12, 40, 41}, calls)), 0u);
  EXPECT_EQ(rates.add(scripted(1, {80, 81, 82, 20, 21}, calls)), 1u);
  auto result = rates.run(2.5, 5);
  ASSERT_TRUE(result) << result.error().message;
  ASSERT_EQ(result->size(), 2u);
  ASSERT_EQ(calls.size(), 10u);
  for (size_t i = 0; i < calls.size(); ++i) {
    EXPECT_EQ(calls[i].first, int(i % 2)) << "call " << i;  // alternating, not back to back
    EXPECT_DOUBLE_EQ(calls[i].second, 0.5) << "call " << i;  // min_seconds / rounds each
  }
  EXPECT_DOUBLE_EQ((*result)[0].lookups_per_second, 41);
  EXPECT_DOUBLE_EQ((*result)[1].lookups_per_second, 82);
  EXPECT_EQ((*result)[0].lookups, 10u + 11 + 12 + 40 + 41);  // totals over every round
  EXPECT_DOUBLE_EQ((*result)[1].seconds, 5);
  EXPECT_EQ((*result)[1].cache_misses, 5u);
}

TEST(InterleavedRates, AFailingRoundStopsTheRunWithItsError) {
  std::vector<std::pair<int, double>> calls;
  InterleavedRates rates;
  rates.add(scripted(0, {1, 2, 3}, calls));
  int failing_calls = 0;
  rates.add([&](double) -> st::Result<LookupRate> {
    if (++failing_calls == 2) return st::make_error(st::ErrorCode::corrupt_data, "tile checksum mismatch");
    return LookupRate{5, 5, 1, 0};
  });
  auto result = rates.run(1, 3);
  ASSERT_FALSE(result);
  EXPECT_EQ(result.error().message, "tile checksum mismatch");
  EXPECT_EQ(calls.size(), 2u);  // round 3 never ran
}

TEST(InterleavedRates, PointRoundsCountLookupsAndMeasureNothingWithoutPoints) {
  std::vector<st::Vec3> none;
  auto empty = st::bench::point_rounds(none, 2, [](const st::Vec3&) { return 1.0; })(0.01);
  ASSERT_TRUE(empty);
  EXPECT_EQ(empty->lookups, 0u);  // returns at once rather than spinning on an empty list
  std::vector<st::Vec3> points(100, st::Vec3{0, 0, 0});
  auto rate = st::bench::point_rounds(points, 2, [](const st::Vec3&) { return 1.0; })(0.01);
  ASSERT_TRUE(rate);
  EXPECT_GT(rate->lookups, 0u);
  EXPECT_GT(rate->lookups_per_second, 0);
}
