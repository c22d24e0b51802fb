// HugePageArray (common/huge_page_array.hpp): assign_zero sizes the array and zeroes every element,
// whether it grows the allocation or reuses it, and an empty array is valid.
#include <gtest/gtest.h>

#include <cstdint>

#include "common/huge_page_array.hpp"

namespace shadowtiles {
namespace {

void expect_all_zero(const HugePageArray<uint64_t>& a) {
  size_t nonzero = 0;
  for (size_t i = 0; i < a.size(); ++i) nonzero += a[i] != 0;
  EXPECT_EQ(nonzero, 0u);
}

TEST(HugePageArray, AssignZeroSizesAndZeroesOnGrowthAndReuse) {
  HugePageArray<uint64_t> a;
  a.assign_zero(0);
  EXPECT_EQ(a.size(), 0u);
  a.assign_zero(1000);
  ASSERT_EQ(a.size(), 1000u);
  expect_all_zero(a);
  for (size_t i = 0; i < a.size(); ++i) a[i] = i + 1;
  a.assign_zero(10);  // reuse: smaller, still zeroed
  ASSERT_EQ(a.size(), 10u);
  expect_all_zero(a);
  for (size_t i = 0; i < a.size(); ++i) a[i] = ~uint64_t(0);
  a.assign_zero(1000);  // reuse up to the old size: the elements written before are zero again
  expect_all_zero(a);
  a.assign_zero(3'000'000);  // growth past the first 2 MiB allocation
  ASSERT_EQ(a.size(), 3'000'000u);
  expect_all_zero(a);
  a[2'999'999] = 7;
  EXPECT_EQ(a[2'999'999], 7u);
}

}  // namespace
}  // namespace shadowtiles
