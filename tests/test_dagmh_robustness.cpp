// The DAG-MH decoder against hostile payloads at several treelet heights, chunk sizes and skip
// levels: every truncation, every single bit flip, random multi-byte corruption, hostile header
// fields, wrong magic and version. Each must give an
// error or a view whose lookups stay in bounds and finite (run under ASan: -DSHADOWTILES_SANITIZE=ON).
// Every trial copies the bytes into an exact-size buffer so a read past the end is caught.
// Generic attacks on the decode path (truncations, a trailing byte, bit flips, garbage) for every
// method are in tests/test_codec_torture.cpp; this file keeps what is specific to the format.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "builder/dagmh_encoder.hpp"
#include "builder/mh_builder.hpp"
#include "builder/mh_synthetic.hpp"
#include "codec/dagmh_decoder.hpp"
#include "codec/dagmh_format.hpp"

namespace shadowtiles {
namespace {

namespace F = dagmh_format;

std::vector<std::vector<uint8_t>> sample_payloads() {
  std::vector<std::vector<uint8_t>> out;
  for (MhSyntheticKind kind : {MhSyntheticKind::steps, MhSyntheticKind::random_intervals,
                               MhSyntheticKind::closed_plane, MhSyntheticKind::all_miss}) {
    for (uint32_t size : {1u, 8u, 32u}) {
      auto tree = build_mh(make_synthetic_tile(kind, size, size + 17));
      for (unsigned height : {2u, 4u}) {
        DagMhOptions o;
        o.treelet_height = height;
        o.chunk_size = height == 2 ? 16 : 32;
        out.push_back(*encode_dagmh(*tree, o));
      }
    }
  }
  return out;
}

void exercise(const DagMhTileView& view) {
  const uint32_t n = view.size();
  for (uint32_t v = 0; v < n; ++v)
    for (uint32_t u = 0; u < n; ++u)
      for (unsigned level : {0u, 1u, 3u, kDagMhAllLevels}) ASSERT_TRUE(std::isfinite(view.lookup(u, v, level)));
  if (n >= 3) {
    (void)view.pcf_lit_count(0, 0, 3, 3, 0.5f, 0.0f);
    (void)view.pcf_lit_count(n - 3, n - 3, 3, 3, 0.5f, 0.0f);
    (void)view.pcf_lit_count(0, 0, n, n, 0.5f, 0.0f);
  }
}

bool try_parse(const std::vector<uint8_t>& bytes) {
  std::vector<uint8_t> exact(bytes);
  bool accepted = false;
  for (unsigned skip : {6u, 2u, 0u}) {
    DagMhParseOptions o;
    o.skip_level = skip;
    auto view = DagMhTileView::parse(std::span<const uint8_t>(exact.data(), exact.size()), o);
    if (!view.ok()) {
      EXPECT_TRUE(view.error().code == ErrorCode::corrupt_data || view.error().code == ErrorCode::unsupported);
      return false;
    }
    exercise(*view);
    accepted = true;
  }
  return accepted;
}


TEST(DagMhRobustness, EveryTruncationIsAnError) {
  for (const auto& p : sample_payloads())
    for (size_t len = 0; len < p.size(); ++len)
      EXPECT_FALSE(try_parse(std::vector<uint8_t>(p.begin(), p.begin() + len))) << "length " << len;
}


TEST(DagMhRobustness, EverySingleBitFlipIsSafe) {
  uint64_t accepted = 0, trials = 0;
  for (const auto& p : sample_payloads())
    for (size_t byte = 0; byte < p.size(); ++byte)
      for (unsigned bit = 0; bit < 8; ++bit) {
        auto q = p;
        q[byte] ^= uint8_t(1u << bit);
        accepted += try_parse(q);
        ++trials;
      }
  // Value bits (representatives, raw floats, multipliers) are legitimately accepted.
  EXPECT_LT(accepted, trials);
  RecordProperty("accepted", std::to_string(accepted) + "/" + std::to_string(trials));
}

TEST(DagMhRobustness, RandomMultiByteCorruptionIsSafe) {
  std::mt19937 rng(5);
  const auto payloads = sample_payloads();
  for (int trial = 0; trial < 20000; ++trial) {
    auto q = payloads[rng() % payloads.size()];
    const unsigned edits = 1 + rng() % 4;
    for (unsigned e = 0; e < edits; ++e) q[rng() % q.size()] = uint8_t(rng());
    try_parse(q);
  }
}

TEST(DagMhRobustness, HostileHeaderFields) {
  for (const auto& p : sample_payloads()) {
    for (size_t field : {F::kOffSize, F::kOffRootRef, F::kOffDagBytes, F::kOffTreeletCount, F::kOffValueCount,
                         F::kOffChunkBytes}) {
      for (uint32_t value : {0u, 1u, 0x7fffffffu, 0xffffffffu, uint32_t(p.size())}) {
        auto q = p;
        std::memcpy(q.data() + field, &value, 4);
        try_parse(q);
      }
    }
    for (size_t field : {F::kOffLevels, F::kOffTreeletHeight, F::kOffRefWidth, F::kOffCountWidth,
                         F::kOffChunkOffsetWidth, F::kOffRootKind, F::kOffChunkSize, F::kOffChunkSize + 1})
      for (unsigned value = 0; value < 256; value += 3) {
        auto q = p;
        q[field] = uint8_t(value);
        try_parse(q);
      }
  }
}

TEST(DagMhRobustness, MagicAndVersion) {
  auto p = sample_payloads()[3];
  auto q = p;
  q[0] = 'X';
  auto r = DagMhTileView::parse(q);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::corrupt_data);
  q = p;
  q[F::kOffVersion] = uint8_t(F::kFormatVersion + 1);
  r = DagMhTileView::parse(q);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::unsupported);
  q = p;
  q[F::kOffVersion] = 0;
  EXPECT_FALSE(DagMhTileView::parse(q).ok());
}


}  // namespace
}  // namespace shadowtiles
