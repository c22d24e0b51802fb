// SST (sparse shadow tree) encoder and decoder on synthetic tiles: every texel decodes inside its
// interval (exhaustive) for planes, steps, noise, misses and intervals only a few ulps wide; the
// plane fit finds planes where they exist; PCF lit counts equal per-texel counting; coarse levels
// are decimations; malformed intervals are refused.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "builder/mh_synthetic.hpp"
#include "builder/sst_encoder.hpp"
#include "builder/sst_plane_fit.hpp"
#include "codec/decoded_tile.hpp"
#include "codec/sst_format.hpp"
#include "codec/sst_tile_view.hpp"
#include "tests/parsed_payload.hpp"

namespace shadowtiles {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

testing::ParsedPayload<SstTileView> encode_and_parse(const TileIntervals& tile) {
  return testing::parse_payload<SstTileView>(encode_sst_tile(tile));
}

uint64_t count_outside(const TileIntervals& tile, const SstTileView& view) {
  uint64_t outside = 0;
  for (uint32_t v = 0; v < tile.size; ++v)
    for (uint32_t u = 0; u < tile.size; ++u) outside += !tile.at(u, v).contains(view.lookup(u, v));
  return outside;
}

// A tilted plane (slopes per texel) with intervals [p - below, p + above] around it.
TileIntervals plane_tile(uint32_t size, double a, double b, double c, float below, float above) {
  TileIntervals tile;
  tile.size = size;
  tile.texels.resize(size_t(size) * size);
  for (uint32_t v = 0; v < size; ++v)
    for (uint32_t u = 0; u < size; ++u) {
      const float p = float(a + b * u + c * v);
      tile.at(u, v) = {p - below, p + above};
    }
  return tile;
}

TEST(Sst, SyntheticTilesAreLosslessAtEverySize) {
  for (MhSyntheticKind kind : {MhSyntheticKind::random_intervals, MhSyntheticKind::noisy_plane,
                               MhSyntheticKind::closed_plane, MhSyntheticKind::steps, MhSyntheticKind::all_miss,
                               MhSyntheticKind::boxes_and_misses}) {
    for (uint32_t size : {1u, 2u, 8u, 64u, 256u}) {
      const TileIntervals tile = make_synthetic_tile(kind, size, 7 * size + 3);
      auto encoded = encode_and_parse(tile);
      ASSERT_TRUE(encoded.ok);
      EXPECT_EQ(count_outside(tile, encoded.view), 0u) << synthetic_kind_name(kind) << " " << size;
      const SstStats& s = encoded.view.stats();
      EXPECT_EQ(s.one_texels + s.constant_texels + s.plane_texels + s.dense_texels, uint64_t(size) * size);
    }
  }
}

TEST(Sst, GenericDecoderServesTheMethod) {
  const TileIntervals tile = make_synthetic_tile(MhSyntheticKind::closed_plane, 128, 11);
  auto bytes = encode_sst_tile(tile);
  ASSERT_TRUE(bytes.ok());
  auto decoded = decode_tile(store::Method::sst, *bytes);
  ASSERT_TRUE(decoded.ok()) << decoded.error().message;
  EXPECT_EQ((*decoded)->size(), 128u);
  uint64_t breakdown = 0;
  for (const auto& part : (*decoded)->size_breakdown()) breakdown += part.bytes;
  EXPECT_EQ(breakdown, bytes->size()) << "the breakdown accounts for every payload byte";
  for (uint32_t v = 0; v < 128; v += 7)
    for (uint32_t u = 0; u < 128; u += 5) EXPECT_TRUE(tile.at(u, v).contains((*decoded)->value(u, v)));
}

TEST(Sst, AllMissTileIsOneLeafPerBlock) {
  const TileIntervals tile = make_synthetic_tile(MhSyntheticKind::all_miss, 512, 1);
  auto encoded = encode_and_parse(tile);
  ASSERT_TRUE(encoded.ok);
  const SstStats& s = encoded.view.stats();
  EXPECT_EQ(s.blocks, 16u);
  EXPECT_EQ(s.one_leaves, 16u);
  EXPECT_EQ(encoded.bytes.size(), sst_format::kHeaderBytes + 16 * 4 + 16 * 2);
  EXPECT_EQ(encoded.view.lookup(17, 300), 1.0f);
}

TEST(Sst, WidePlaneIsOnePlanePerBlock) {
  // Steep and shallow slopes, both signs; 1e-4 of slack around the plane.
  for (auto [b, c] : {std::pair{2.4e-4, -1.1e-4}, std::pair{-3e-3, 5e-3}, std::pair{1e-7, 0.0}}) {
    const TileIntervals tile = plane_tile(256, 0.4, b, c, 1e-4f, 1e-4f);
    auto encoded = encode_and_parse(tile);
    ASSERT_TRUE(encoded.ok);
    const SstStats& s = encoded.view.stats();
    EXPECT_EQ(s.plane_leaves + s.constant_leaves, 4u) << "b=" << b << " c=" << c;
    EXPECT_EQ(s.internal_nodes, 0u);
    EXPECT_EQ(count_outside(tile, encoded.view), 0u);
  }
}

TEST(Sst, PlanesFitIntervalsWithOneSidedSlack) {
  // The plane must lie at the top or the bottom edge of every interval: the fit has to centre it.
  const TileIntervals below = plane_tile(128, 0.3, 1e-3, 2e-3, 2e-5f, 0.0f);
  const TileIntervals above = plane_tile(128, 0.3, 1e-3, 2e-3, 0.0f, 2e-5f);
  for (const TileIntervals* tile : {&below, &above}) {
    auto plane = fit_sst_plane(*tile, 0, 0, 128);
    ASSERT_TRUE(plane.has_value());
    EXPECT_TRUE(sst_plane_fits(*tile, 0, 0, 128, *plane));
  }
}

TEST(Sst, IntervalsAFewUlpsWideStayLossless) {
  // Precision loss of the quantised plane must never move a value outside its interval: intervals
  // of 0..4 ulps around a tilted plane, where the 24-bit offset and 16-bit slopes cannot hit
  // every texel; the encoder must notice (exact re-check) and fall back.
  std::mt19937 rng(5);
  for (int ulps : {0, 1, 2, 4}) {
    TileIntervals tile = plane_tile(256, 0.25, 3.1e-4, -1.7e-4, 0.0f, 0.0f);
    for (auto& t : tile.texels) {  // the interval reaches k ulps above or below the plane's float
      const bool up = rng() % 2;
      for (int k = 0; k < ulps; ++k) {
        if (up) t.upper = std::nextafter(t.upper, kInf);
        else t.lower = std::nextafter(t.lower, -kInf);
      }
    }
    auto encoded = encode_and_parse(tile);
    ASSERT_TRUE(encoded.ok);
    EXPECT_EQ(count_outside(tile, encoded.view), 0u) << ulps << " ulps";
  }
}

TEST(Sst, FitterNeverReturnsAPlaneThatFails) {
  // Random regions of random kinds: whatever the fitter returns must pass the exact check.
  std::mt19937 rng(9);
  int planes = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const uint32_t side = 1u << (rng() % 6);
    TileIntervals tile = plane_tile(side, 0.1 + 0.8 * (rng() % 1000) / 1000.0, ((rng() % 2001) - 1000.0) * 1e-6,
                                    ((rng() % 2001) - 1000.0) * 1e-6, float(rng() % 100) * 1e-7f,
                                    float(rng() % 100) * 1e-7f);
    for (auto& t : tile.texels)
      if (rng() % 50 == 0) t = {1.0f, kInf};
    if (auto plane = fit_sst_plane(tile, 0, 0, side)) {
      ++planes;
      EXPECT_TRUE(sst_plane_fits(tile, 0, 0, side, *plane));
    }
  }
  EXPECT_GT(planes, 30) << "the fitter finds planes for some of these regions";
}

TEST(Sst, StepsUseConstantsAndPlanes) {
  const TileIntervals tile = make_synthetic_tile(MhSyntheticKind::steps, 256, 3);
  auto encoded = encode_and_parse(tile);
  ASSERT_TRUE(encoded.ok);
  const SstStats& s = encoded.view.stats();
  EXPECT_GT(s.constant_leaves + s.plane_leaves, 0u);
  EXPECT_LT(encoded.bytes.size(), tile.texels.size() * 4) << "smaller than a float map";
}

TEST(Sst, LitCountEqualsPerTexelCounting) {
  for (MhSyntheticKind kind : {MhSyntheticKind::random_intervals, MhSyntheticKind::closed_plane,
                               MhSyntheticKind::steps, MhSyntheticKind::boxes_and_misses}) {
    const uint32_t size = 256;
    const TileIntervals tile = make_synthetic_tile(kind, size, 21);
    auto encoded = encode_and_parse(tile);
    ASSERT_TRUE(encoded.ok);
    const SstTileView& view = encoded.view;
    std::mt19937 rng(4);
    for (int trial = 0; trial < 400; ++trial) {
      const uint32_t kw = 1 + rng() % (trial % 10 == 0 ? 200 : 9), kh = 1 + rng() % (trial % 10 == 0 ? 200 : 9);
      const uint32_t u0 = rng() % (size - kw + 1), v0 = rng() % (size - kh + 1);
      // Thresholds: random, and exactly a texel's value (the boundary case of lit: threshold <= value).
      const float threshold = trial % 2 ? float(rng() % 1000) / 999.0f : view.lookup(u0 + kw / 2, v0 + kh / 2);
      uint32_t expected = 0;
      for (uint32_t v = v0; v < v0 + kh; ++v)
        for (uint32_t u = u0; u < u0 + kw; ++u) expected += threshold <= view.lookup(u, v);
      ASSERT_EQ(view.lit_count(u0, v0, kw, kh, threshold), expected)
          << synthetic_kind_name(kind) << " box " << u0 << "," << v0 << " " << kw << "x" << kh;
    }
    EXPECT_EQ(view.lit_count(0, 0, size, size, -1.0f), size * size);
    EXPECT_EQ(view.lit_count(0, 0, size, size, 1e30f), 0u);
  }
}

TEST(Sst, CoarseLevelsAreDecimations) {
  const TileIntervals tile = make_synthetic_tile(MhSyntheticKind::boxes_and_misses, 256, 8);
  auto encoded = encode_and_parse(tile);
  ASSERT_TRUE(encoded.ok);
  const SstTileView& view = encoded.view;
  ASSERT_EQ(view.levels(), 8u);
  std::mt19937 rng(1);
  for (int trial = 0; trial < 2000; ++trial) {
    const uint32_t u = rng() % 256, v = rng() % 256;
    const unsigned level = rng() % 10;
    const uint32_t cell = level >= 8 ? 1 : 256u >> level;
    EXPECT_EQ(view.lookup(u, v, level), view.lookup(u / cell * cell, v / cell * cell));
  }
  EXPECT_EQ(view.lookup(200, 100, 0), view.lookup(0, 0));
}

TEST(Sst, MalformedIntervalsAreRefused) {
  TileIntervals tile = make_synthetic_tile(MhSyntheticKind::closed_plane, 16, 2);
  auto nan_tile = tile;
  nan_tile.at(3, 4).upper = std::nanf("");
  auto inverted = tile;
  inverted.at(1, 1) = {0.6f, 0.5f};
  auto infinite_lower = tile;
  infinite_lower.at(0, 0).lower = -kInf;
  auto not_square = tile;
  not_square.texels.pop_back();
  auto not_power_of_two = plane_tile(12, 0.5, 0, 0, 0.1f, 0.1f);
  for (const TileIntervals* bad : {&nan_tile, &inverted, &infinite_lower, &not_square, &not_power_of_two}) {
    auto result = encode_sst_tile(*bad);
    ASSERT_FALSE(result.ok());
    EXPECT_EQ(result.error().code, ErrorCode::invalid_input);
  }
}

}  // namespace
}  // namespace shadowtiles
