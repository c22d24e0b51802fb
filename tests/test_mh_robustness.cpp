// The MH decoder against hostile payloads, skip-list payloads (top trees) included: bit flips,
// random corruption, hostile header fields, wrong magic and version. Each must give an error or a view whose lookups stay in bounds (run under ASan:
// -DSHADOWTILES_SANITIZE=ON). Every trial copies the bytes into an exact-size buffer so a read past
// the end is caught.
// Generic attacks on the decode path (truncations, a trailing byte, bit flips, garbage) for every
// method are in tests/test_codec_torture.cpp; this file keeps what is specific to the format.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>

#include "builder/mh_builder.hpp"
#include "builder/mh_encoder.hpp"
#include "builder/mh_synthetic.hpp"
#include "builder/mmh_merger.hpp"
#include "codec/mh_decoder.hpp"
#include "codec/mh_format.hpp"
#include "tests/payload_attacks.hpp"

namespace shadowtiles {
namespace {

// MH, MMH and MMH with a skip list.
testing::Payloads encode_all(const TileIntervals& tile) {
  auto tree = build_mh(tile);
  auto merged = merge_mmh(*tree);
  MhEncodeOptions skip;
  skip.embed_skip_list = true;
  skip.skip_level = 2;
  return {*encode_mh(*tree), *encode_mh(*merged), *encode_mh(*merged, skip)};
}

testing::Payloads sample_payloads() {
  return testing::encode_sample_tiles({MhSyntheticKind::steps, MhSyntheticKind::random_intervals,
                                       MhSyntheticKind::boxes_and_misses, MhSyntheticKind::all_miss},
                                      encode_all);
}

bool try_parse(const std::vector<uint8_t>& bytes) {
  return testing::parse_exact(
      bytes, [](std::span<const uint8_t> exact) { return MhTileView::parse(exact); },
      [](const MhTileView& view) { testing::exercise_hierarchy_view(view, kMhAllLevels); });
}

TEST(MhRobustness, EverySingleBitFlipIsSafe) {
  // Flipped value bits are legitimately accepted (a different finite value); structure flips are not.
  testing::expect_every_bit_flip_safe(sample_payloads(), try_parse);
}

TEST(MhRobustness, RandomMultiByteCorruptionIsSafe) {
  testing::random_multi_byte_corruption(sample_payloads(), try_parse, 20000, 5);
}

// Header fields set to extreme values (offsets, counts, sizes) with the payload size kept.
TEST(MhRobustness, HostileHeaderFields) {
  namespace F = mh_format;
  testing::hostile_header_fields(sample_payloads(),
                                 {F::kOffSize, F::kOffRootBlock, F::kOffStreamBytes, F::kOffBlockCount,
                                  F::kOffRecordCount, F::kOffValueCount},
                                 {F::kOffLevels, F::kOffOffsetWidth, F::kOffSkipLevel, F::kOffRootMask}, try_parse);
}

// Where each record of a payload without a skip list sits: the record's byte offset in the payload
// and the block offset it holds (the payload's blocks visited in stream order, as the decoder does).
struct RecordSite {
  size_t at;        // payload offset of the record's mask byte
  uint32_t target;  // stream offset of the block it references
};
std::vector<RecordSite> record_sites(const std::vector<uint8_t>& payload) {
  namespace F = mh_format;
  const unsigned W = payload[F::kOffOffsetWidth];
  uint32_t stream_bytes;
  std::memcpy(&stream_bytes, &payload[F::kOffStreamBytes], 4);  // little-endian hosts (the tests')
  std::map<uint32_t, uint8_t> mask_of{{0, payload[F::kOffRootMask]}};
  std::vector<RecordSite> sites;
  for (uint32_t offset = 0; offset < stream_bytes;) {
    const uint8_t mask = mask_of.at(offset);
    for (unsigned r = 0; r < F::branch_children(mask); ++r) {
      const size_t at = F::kHeaderBytes + offset + r * F::record_bytes(W);
      uint32_t target = 0;
      std::memcpy(&target, &payload[at + 1], W);
      mask_of[target] = payload[at];
      sites.push_back({at, target});
    }
    offset += uint32_t(F::block_bytes(mask, W));
  }
  return sites;
}

void set_target(std::vector<uint8_t>& payload, const RecordSite& site, uint32_t target) {
  std::memcpy(&payload[site.at + 1], &target, payload[mh_format::kOffOffsetWidth]);
}

// The stream's structure is checked, not just kept in bounds: a reference into the middle of a block,
// backwards, or to a shared block under another mask is an error, also where every block start is
// still referenced (only the count of distinct references finds the first case then).
TEST(MhRobustness, StructuralDamageIsAnError) {
  auto tile = make_synthetic_tile(MhSyntheticKind::steps, 64, 3);
  auto merged = merge_mmh(*build_mh(tile));
  const std::vector<uint8_t> payload = *encode_mh(*merged);
  ASSERT_TRUE(MhTileView::parse(payload));
  const std::vector<RecordSite> sites = record_sites(payload);
  ASSERT_GT(sites.size(), 4u);
  std::map<uint32_t, int> references;
  for (const RecordSite& site : sites) ++references[site.target];
  auto shared = std::find_if(sites.begin(), sites.end(), [&](const RecordSite& s) { return references[s.target] > 1; });
  ASSERT_NE(shared, sites.end()) << "the sample needs a shared block (MMH)";
  auto expect_corrupt = [](const std::vector<uint8_t>& bytes, const char* what) {
    auto view = MhTileView::parse(bytes);
    ASSERT_FALSE(view) << what;
    EXPECT_EQ(view.error().code, ErrorCode::corrupt_data) << what;
  };
  {
    std::vector<uint8_t> bad = payload;  // the block keeps its other reference
    set_target(bad, *shared, shared->target + 1);
    bad[shared->at] = 0x01;  // one leaf child: a shallow height, so only the reference count can see it
    expect_corrupt(bad, "a reference inside a shared block");
  }
  {
    // The children's codes rotated: the same counts of records and values, so the same block size,
    // and only the check that a shared block's references agree on its mask can see it.
    const uint8_t mask = payload[shared->at];
    uint8_t other = mask;
    for (unsigned r = 2; r < 8 && other == mask; r += 2) other = uint8_t((mask << r) | (mask >> (8 - r)));
    ASSERT_NE(other, mask) << "the sample's shared block needs children of more than one kind";
    std::vector<uint8_t> bad = payload;
    bad[shared->at] = other;
    expect_corrupt(bad, "a shared block under another mask");
  }
  {
    std::vector<uint8_t> bad = payload;
    set_target(bad, sites.back(), 0);
    expect_corrupt(bad, "a backward reference");
  }
  {
    std::vector<uint8_t> bad = payload;  // the only reference of a block points one byte further
    auto single = std::find_if(sites.begin(), sites.end(), [&](const RecordSite& s) { return references[s.target] == 1; });
    ASSERT_NE(single, sites.end());
    set_target(bad, *single, single->target + 1);
    expect_corrupt(bad, "a gap where a block was");
  }
}

TEST(MhRobustness, MagicAndVersion) {
  testing::expect_magic_and_version_checked(sample_payloads()[3], mh_format::kOffVersion, mh_format::kFormatVersion,
                                            [](const std::vector<uint8_t>& q) { return MhTileView::parse(q); });
}

}  // namespace
}  // namespace shadowtiles
