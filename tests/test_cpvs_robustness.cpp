// CPVS decoder on untrusted bytes: every truncation is refused; every single-bit flip is either
// refused or gives a view whose every lookup stays in bounds (run under ASan/UBSan to prove it);
// random garbage and hand-made hostile headers are refused.
// Generic attacks on the decode path (truncations, a trailing byte, bit flips, garbage) for every
// method are in tests/test_codec_torture.cpp; this file keeps what is specific to the format.
#include <gtest/gtest.h>

#include <random>

#include "builder/cpvs_encoder.hpp"
#include "codec/cpvs_decoder.hpp"
#include "codec/cpvs_tile_view.hpp"
#include "tests/payload_attacks.hpp"

namespace shadowtiles {
namespace {

std::vector<uint8_t> sample_payload(cpvs::LeafLayout layout) {
  TileIntervals tile{16, std::vector<DepthInterval>(256)};
  std::mt19937 rng(3);
  for (uint32_t v = 0; v < 16; ++v)
    for (uint32_t u = 0; u < 16; ++u) {
      float lower = u < 3 ? 1.0f : 0.1f + 0.05f * float((u * 7 + v * 3) % 11) + 0.001f * float(rng() % 100);
      float upper = lower < 1.0f && (u + v) % 3 == 0 ? lower + 0.15f : lower;
      tile.at(u, v) = {lower, lower >= 1.0f ? std::numeric_limits<float>::infinity() : upper};
    }
  CpvsBuildOptions options;
  options.layout = layout;
  auto payload = encode_cpvs_tile(tile, 32, options);
  EXPECT_TRUE(payload.ok());
  return *payload;
}

// Every lookup kind over the whole tile: must not crash or read out of bounds.
uint64_t exercise(const CpvsTileView& view) {
  uint64_t lit = 0;
  for (uint32_t v = 0; v < view.size(); ++v)
    for (uint32_t u = 0; u < view.size(); ++u) {
      lit += view.first_shadowed_step(u, v);
      for (uint32_t z = 0; z < view.depth_steps(); z += 3) lit += view.lit_at_step(u, v, z);
    }
  for (float t : {0.1f, 0.5f, 0.9f}) lit += view.lit_count(0, 0, view.size(), view.size(), t);
  return lit;
}

TEST(CpvsRobustness, TheSamplePayloadHasNodesAndLeaves) {
  for (auto layout : {cpvs::LeafLayout::slab8, cpvs::LeafLayout::cube4}) {
    auto view = CpvsTileView::parse(sample_payload(layout));
    ASSERT_TRUE(view.ok()) << view.error().message;
    EXPECT_GT(view->stats().nodes, 3u);
    EXPECT_GT(view->stats().leaves, 3u);
  }
}


TEST(CpvsRobustness, EveryBitFlipIsRefusedOrStaysInBounds) {
  for (auto layout : {cpvs::LeafLayout::slab8, cpvs::LeafLayout::cube4}) {
    const std::vector<uint8_t> payload = sample_payload(layout);
    uint64_t refused = 0, accepted = 0, sink = 0;
    for (size_t bit = 0; bit < payload.size() * 8; ++bit) {
      std::vector<uint8_t> flipped = payload;
      flipped[bit / 8] ^= uint8_t(1u << (bit % 8));
      // Accepted e.g. for a flipped leaf bit or child code 0 <-> 1: still well-formed.
      const bool accepted_flip = testing::parse_exact(
          flipped, [](std::span<const uint8_t> exact) { return CpvsTileView::parse(exact); },
          [&](const CpvsTileView& view) { sink += exercise(view); });
      ++(accepted_flip ? accepted : refused);
    }
    EXPECT_GT(refused, 0u);
    EXPECT_GT(accepted, 0u);
    EXPECT_GT(sink, 0u);
  }
}

TEST(CpvsRobustness, RandomGarbageAndHostileHeadersAreRefused) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<uint8_t> bytes(rng() % 200);
    for (auto& b : bytes) b = uint8_t(rng());
    if (bytes.size() >= 4 && trial % 2) std::copy(cpvs::kMagic, cpvs::kMagic + 4, bytes.begin());
    auto view = CpvsTileView::parse(bytes);
    if (view.ok()) exercise(*view);
  }
  std::vector<uint8_t> payload = sample_payload(cpvs::LeafLayout::slab8);
  auto with = [&](size_t offset, uint32_t value) {
    std::vector<uint8_t> copy = payload;
    bytes::store_le<uint32_t>(copy.data() + offset, value);
    return CpvsTileView::parse(copy).ok();
  };
  EXPECT_FALSE(with(cpvs::kOffDepthSteps, 1u << 30)) << "depth steps beyond 2^20";
  EXPECT_FALSE(with(cpvs::kOffDepthSteps, 48)) << "not a power of two";
  EXPECT_FALSE(with(cpvs::kOffTileSize, 64)) << "tile wider than the depth cube";
  EXPECT_FALSE(with(cpvs::kOffLevelCount, 0xFFFFFFFFu));
  EXPECT_FALSE(with(cpvs::kOffLeafCount, 0xFFFFFFFFu)) << "sizes must add up";
  EXPECT_FALSE(with(cpvs::kHeaderBytes, 0xFFFFFFF0u)) << "a level larger than the payload";
}

}  // namespace
}  // namespace shadowtiles
