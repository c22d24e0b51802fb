// The codec-torture suite: every method in the method table (raw included) through the one decode
// path (decode_tile) against hostile payloads — every truncation, a trailing byte, every single bit
// flip, random multi-byte corruption and garbage behind a real header. Each must be an error
// (corrupt_data or unsupported) or a tile whose every lookup stays in bounds and finite (run under
// ASan: -DSHADOWTILES_SANITIZE=ON). Every trial copies the bytes into an exact-size heap buffer so a
// read past the end is caught. Format-specific attacks (hostile header fields, magic and version)
// stay in each method's own tests/test_<method>_robustness.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "builder/mh_synthetic.hpp"
#include "builder/tile_encoder.hpp"
#include "codec/decoded_tile.hpp"
#include "store/method.hpp"

namespace shadowtiles {
namespace {

using store::Method;

struct Sample {
  TileIntervals intervals;
  std::vector<uint8_t> payload;
};

// Tiles with every feature that shapes a payload: edges, zero-width and wide intervals, misses.
std::vector<Sample> samples_for(Method method) {
  std::vector<Sample> out;
  for (MhSyntheticKind kind : {MhSyntheticKind::steps, MhSyntheticKind::random_intervals,
                               MhSyntheticKind::closed_plane, MhSyntheticKind::boxes_and_misses,
                               MhSyntheticKind::all_miss}) {
    for (uint32_t size : {1u, 8u, 16u}) {
      TileEncodeOptions options;
      options.map_resolution = 64;
      TileIntervals intervals = make_synthetic_tile(kind, size, size + 17);
      auto encoded = encode_tile({method}, intervals, options);
      EXPECT_TRUE(encoded.ok()) << encoded.error().message;
      if (!encoded) continue;
      out.push_back({std::move(intervals), std::move(encoded->payloads.front().payload)});
    }
  }
  return out;
}

// Every read path of an accepted tile. Values must be finite; a method that stores visibility
// reports +inf for a column that is never shadowed (codec/cpvs_decoder.hpp), never NaN.
bool sane(float value, bool visibility) { return visibility ? !std::isnan(value) && value != -INFINITY : std::isfinite(value); }

void exercise(const DecodedTile& tile, bool visibility) {
  const uint32_t n = tile.size();
  std::vector<TexelQuery> queries;
  for (uint32_t v = 0; v < n; ++v)
    for (uint32_t u = 0; u < n; ++u) {
      for (unsigned level : {0u, 1u, 3u, 255u}) ASSERT_TRUE(sane(tile.value(u, v, level), visibility)) << u << "," << v;
      const auto s = tile.sample(u, v, 0.5f);
      ASSERT_TRUE(sane(s.value, visibility));
      (void)tile.lit(u, v, 0.25f);
      if ((u + v) % 3 == 0) queries.push_back({u, v, 0.5f});
    }
  std::vector<uint8_t> lit(queries.size());
  tile.lit_sorted(queries, 255, lit.data());
  (void)tile.lit_count(0, 0, n, n, 0.5f);
  if (n >= 3) {
    (void)tile.lit_count(0, 0, 3, 3, 0.5f);
    (void)tile.lit_count(n - 3, n - 3, 3, 3, 0.5f);
  }
  (void)tile.size_breakdown();
  (void)tile.structure_counts();
  (void)tile.memory_bytes();
}

class CodecTorture : public ::testing::TestWithParam<Method> {
 protected:
  void SetUp() override {
    if (!builder_supports(GetParam())) GTEST_FAIL() << store::method_name(GetParam()) << ": no encoder in this build";
    samples_ = samples_for(GetParam());
    ASSERT_FALSE(samples_.empty());
  }
  // True when accepted (and exercised); an error must be corrupt_data or unsupported.
  bool try_decode(const std::vector<uint8_t>& bytes) const {
    std::vector<uint8_t> exact(bytes);
    auto tile = decode_tile(GetParam(), std::span<const uint8_t>(exact.data(), exact.size()));
    if (!tile.ok()) {
      EXPECT_TRUE(tile.error().code == ErrorCode::corrupt_data || tile.error().code == ErrorCode::unsupported)
          << tile.error().message;
      return false;
    }
    exercise(**tile, store::method_properties(GetParam()).stores_visibility);
    return true;
  }
  std::vector<Sample> samples_;
};

// Originals decode, and an interval-exact method answers inside every texel's interval.
TEST_P(CodecTorture, OriginalsDecodeInsideTheirIntervals) {
  const bool exact = store::method_properties(GetParam()).interval_exact;
  for (const Sample& s : samples_) {
    auto tile = decode_tile(GetParam(), s.payload);
    ASSERT_TRUE(tile.ok()) << tile.error().message;
    ASSERT_EQ((*tile)->size(), s.intervals.size);
    exercise(**tile, store::method_properties(GetParam()).stores_visibility);
    if (!exact) continue;
    for (uint32_t v = 0; v < s.intervals.size; ++v)
      for (uint32_t u = 0; u < s.intervals.size; ++u) {
        const float x = (*tile)->value(u, v);
        const DepthInterval& d = s.intervals.at(u, v);
        ASSERT_TRUE(d.lower <= x && x <= d.upper) << "texel " << u << "," << v << ": " << x << " outside ["
                                                  << d.lower << ", " << d.upper << "]";
      }
  }
}

TEST_P(CodecTorture, EveryTruncationIsAnError) {
  for (const Sample& s : samples_)
    for (size_t length = 0; length < s.payload.size(); ++length)
      ASSERT_FALSE(try_decode(std::vector<uint8_t>(s.payload.begin(), s.payload.begin() + length)))
          << "length " << length << " of " << s.payload.size();
}

TEST_P(CodecTorture, TrailingBytesAreAnError) {
  for (Sample s : samples_) {
    s.payload.push_back(0);
    EXPECT_FALSE(try_decode(s.payload));
  }
}

TEST_P(CodecTorture, EverySingleBitFlipIsSafe) {
  uint64_t accepted = 0, trials = 0;
  for (const Sample& s : samples_)
    for (size_t bit = 0; bit < s.payload.size() * 8; ++bit) {
      auto q = s.payload;
      q[bit / 8] ^= uint8_t(1u << (bit % 8));
      accepted += try_decode(q);
      ++trials;
    }
  // Value bits may legitimately flip into another valid value; structure bits may not.
  EXPECT_LT(accepted, trials);
  RecordProperty("accepted", std::to_string(accepted) + "/" + std::to_string(trials));
}

TEST_P(CodecTorture, RandomMultiByteCorruptionIsSafe) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 5000; ++trial) {
    auto q = samples_[rng() % samples_.size()].payload;
    if (q.empty()) continue;
    const unsigned edits = 1 + rng() % 4;
    for (unsigned e = 0; e < edits; ++e) q[rng() % q.size()] = uint8_t(rng());
    try_decode(q);
  }
}

// Garbage behind a real payload's first bytes (magic, version), so parsing gets past the header.
TEST_P(CodecTorture, GarbageBehindARealHeaderIsSafe) {
  std::mt19937 rng(9);
  const std::vector<uint8_t>& real = samples_.back().payload;
  for (int trial = 0; trial < 3000; ++trial) {
    std::vector<uint8_t> q(rng() % 300);
    for (auto& b : q) b = uint8_t(rng());
    const size_t keep = std::min<size_t>({q.size(), real.size(), size_t(rng() % 24)});
    std::copy(real.begin(), real.begin() + keep, q.begin());
    try_decode(q);
  }
}

INSTANTIATE_TEST_SUITE_P(EveryMethod, CodecTorture,
                         ::testing::ValuesIn(store::all_methods().begin(), store::all_methods().end()),
                         [](const ::testing::TestParamInfo<Method>& info) {
                           return std::string(store::method_name(info.param));
                         });

}  // namespace
}  // namespace shadowtiles
