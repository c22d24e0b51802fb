// Format-specific attacks on one codec's parser, shared by the test_<format>_robustness files:
// every single bit flip, random multi-byte edits, header fields set to extreme values, and the magic
// and version checks. `try_parse(bytes)` parses (exact-size copy, so ASan sees overruns), exercises
// an accepted view and returns whether it was accepted. The generic attacks every method gets through
// decode_tile are in tests/test_codec_torture.cpp.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <functional>
#include <initializer_list>
#include <random>
#include <string>
#include <vector>

#include "common/result.hpp"

namespace shadowtiles::testing {

using Payloads = std::vector<std::vector<uint8_t>>;
using TryParse = std::function<bool(const std::vector<uint8_t>&)>;

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
