// Format-specific attacks on one codec's parser, shared by the test_<format>_robustness files:
// every single bit flip, random multi-byte edits, header fields set to extreme values, and the magic
// and version checks. `try_parse(bytes)` parses (exact-size copy, so ASan sees overruns: parse_exact),
// exercises an accepted view and returns whether it was accepted. Also the small synthetic tiles the
// payloads are encoded from (encode_sample_tiles) and the read paths of a hierarchy view (MH, DAG-MH). The generic attacks
// every method gets through decode_tile are in tests/test_codec_torture.cpp.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <initializer_list>
#include <random>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "builder/mh_synthetic.hpp"
#include "common/result.hpp"

namespace shadowtiles::testing {

using Payloads = std::vector<std::vector<uint8_t>>;
using TryParse = std::function<bool(const std::vector<uint8_t>&)>;

// The payloads to attack: `encode(tile)` (a Payloads) of the synthetic tiles of every kind in `kinds`
// at 1, 8 and 32 texels a side (seed: size + 17), kind by kind.
template <typename Encode>
Payloads encode_sample_tiles(std::initializer_list<MhSyntheticKind> kinds, Encode encode) {
  Payloads out;
  for (MhSyntheticKind kind : kinds)
    for (uint32_t size : {1u, 8u, 32u})
      for (std::vector<uint8_t>& p : encode(make_synthetic_tile(kind, size, size + 17))) out.push_back(std::move(p));
  return out;
}

// Parses an exact-size heap copy of `bytes` (ASan sees any overrun) with `parse(span)`. A refusal
// must be corrupt_data or unsupported; an accepted result goes to `exercise`. Returns whether it was
// accepted.
template <typename Parse, typename Exercise>
bool parse_exact(const std::vector<uint8_t>& bytes, Parse parse, Exercise exercise) {
  const std::vector<uint8_t> exact(bytes);
  auto parsed = parse(std::span<const uint8_t>(exact.data(), exact.size()));
  if (!parsed.ok()) {
    EXPECT_TRUE(parsed.error().code == ErrorCode::corrupt_data || parsed.error().code == ErrorCode::unsupported)
        << parsed.error().message;
    return false;
  }
  exercise(*parsed);
  return true;
}

// Every read path of an accepted hierarchy view (MH, DAG-MH): every texel at levels 0, 1, 3 and
// `all_levels` must read finite; PCF boxes at both corners and over the whole tile stay in bounds.
template <typename View>
void exercise_hierarchy_view(const View& view, unsigned all_levels) {
  const uint32_t n = view.size();
  for (uint32_t v = 0; v < n; ++v)
    for (uint32_t u = 0; u < n; ++u)
      for (unsigned level : {0u, 1u, 3u, all_levels}) ASSERT_TRUE(std::isfinite(view.lookup(u, v, level)));
  if (n >= 3) {
    (void)view.pcf_lit_count(0, 0, 3, 3, 0.5f, 0.0f);
    (void)view.pcf_lit_count(n - 3, n - 3, 3, 3, 0.5f, 0.0f);
    (void)view.pcf_lit_count(0, 0, n, n, 0.5f, 0.0f);
  }
}

// Flips every bit of every payload once; value bits may be accepted, structure bits must not all be.
inline void expect_every_bit_flip_safe(const Payloads& payloads, const TryParse& try_parse) {
  uint64_t accepted = 0, trials = 0;
  for (const auto& p : payloads)
    for (size_t byte = 0; byte < p.size(); ++byte)
      for (unsigned bit = 0; bit < 8; ++bit) {
        auto q = p;
        q[byte] ^= uint8_t(1u << bit);
        accepted += try_parse(q);
        ++trials;
      }
  EXPECT_LT(accepted, trials);
  ::testing::Test::RecordProperty("accepted", std::to_string(accepted) + "/" + std::to_string(trials));
}

// `trials` payloads, each with 1-4 random bytes overwritten.
inline void random_multi_byte_corruption(const Payloads& payloads, const TryParse& try_parse, int trials,
                                         unsigned seed) {
  std::mt19937 rng(seed);
  for (int trial = 0; trial < trials; ++trial) {
    auto q = payloads[rng() % payloads.size()];
    const unsigned edits = 1 + rng() % 4;
    for (unsigned e = 0; e < edits; ++e) q[rng() % q.size()] = uint8_t(rng());
    try_parse(q);
  }
}

// 32-bit header fields set to 0, 1, 2^31 - 1, 2^32 - 1 and the payload's size; 8-bit fields to every
// third value. Safety only: try_parse's own checks (errors are corrupt_data/unsupported, accepted views
// stay in bounds) are the assertions.
inline void hostile_header_fields(const Payloads& payloads, std::initializer_list<size_t> u32_fields,
                                  std::initializer_list<size_t> u8_fields, const TryParse& try_parse) {
  for (const auto& p : payloads) {
    for (size_t field : u32_fields)
      for (uint32_t value : {0u, 1u, 0x7fffffffu, 0xffffffffu, uint32_t(p.size())}) {
        auto q = p;
        std::memcpy(q.data() + field, &value, 4);
        try_parse(q);
      }
    for (size_t field : u8_fields)
      for (unsigned value = 0; value < 256; value += 3) {
        auto q = p;
        q[field] = uint8_t(value);
        try_parse(q);
      }
  }
}

// A wrong magic is corrupt_data, a newer version unsupported, version 0 refused.
template <typename Parse>
void expect_magic_and_version_checked(const std::vector<uint8_t>& payload, size_t version_offset,
                                      uint8_t format_version, Parse parse) {
  auto q = payload;
  q[0] = 'X';
  auto r = parse(q);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::corrupt_data);
  q = payload;
  q[version_offset] = uint8_t(format_version + 1);
  r = parse(q);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::unsupported);
  q = payload;
  q[version_offset] = 0;
  EXPECT_FALSE(parse(q).ok());
}

}  // namespace shadowtiles::testing
