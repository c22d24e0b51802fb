// stable_sort_by_key (builder/stable_key_sort.hpp) against std::stable_sort by key: keys that differ
// in every digit, only in high or only in low digits, all equal, and many ties (the tile's edge keys:
// two triangles per shared edge, pushed in value order), including keys with the top bits set.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include "builder/stable_key_sort.hpp"

namespace shadowtiles {
namespace {

using Items = std::vector<std::pair<uint64_t, uint32_t>>;

Items reference_order(Items items) {
  std::stable_sort(items.begin(), items.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  return items;
}

Items random_items(size_t n, uint64_t key_mask, uint64_t distinct, uint32_t seed) {
  std::mt19937_64 random(seed);
  std::vector<uint64_t> keys(distinct);
  for (uint64_t& k : keys) k = random() & key_mask;
  Items items(n);
  for (size_t i = 0; i < n; ++i) items[i] = {keys[random() % distinct], uint32_t(i)};
  return items;
}

TEST(StableKeySort, MatchesStableSortByKey) {
  struct Case {
    const char* what;
    uint64_t mask, distinct;
  };
  const Case cases[] = {
      {"every bit", ~uint64_t(0), 5000},
      {"low digit only", 0x7ffull, 300},
      {"high bits only", 0xfff0000000000000ull, 200},
      {"edge keys (two 20-bit ids)", 0x000fffff000fffffull, 3000},
      {"digits 2 and 4 only", (0x7ffull << 22) | (0x7ffull << 44), 1000},
      {"all equal", ~uint64_t(0), 1},
  };
  for (const Case& c : cases)
    for (size_t n : {0u, 1u, 2u, 17u, 10000u}) {
      Items items = random_items(n, c.mask, c.distinct, uint32_t(n) + 7);
      const Items expected = reference_order(items);
      stable_sort_by_key(items);
      EXPECT_EQ(items, expected) << c.what << ", " << n << " items";
    }
}

TEST(StableKeySort, TiesKeepTheirOrderWhenValuesDescend) {
  Items items;
  for (uint32_t i = 0; i < 4096; ++i) items.push_back({uint64_t(i % 3) << 40 | (i % 5), 4096 - i});
  const Items expected = reference_order(items);
  stable_sort_by_key(items);
  EXPECT_EQ(items, expected);
}

}  // namespace
}  // namespace shadowtiles
