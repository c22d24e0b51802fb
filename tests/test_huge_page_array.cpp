// HugePageArray (common/huge_page_array.hpp): assign_zero sizes the array and zeroes every element,
// whether it grows the allocation or reuses it, and an empty array is valid; arrays of 2 MiB and more
// start on a huge-page boundary, smaller ones on a cache line; a move hands the elements over.
#include <gtest/gtest.h>

#include <cstdint>
#include <utility>

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

TEST(HugePageArray, AlignsLargeArraysToHugePagesAndSmallOnesToCacheLines) {
  HugePageArray<float> small, large;
  small.resize_for_overwrite(1000);
  large.resize_for_overwrite((size_t(2) << 20) / sizeof(float));  // exactly one huge page
  EXPECT_EQ(reinterpret_cast<uintptr_t>(small.data()) % 64, 0u);
  EXPECT_EQ(reinterpret_cast<uintptr_t>(large.data()) % (size_t(2) << 20), 0u);
}

TEST(HugePageArray, MoveHandsTheElementsOver) {
  HugePageArray<uint32_t> a;
  a.resize_for_overwrite(5000);
  for (size_t i = 0; i < a.size(); ++i) a[i] = uint32_t(i * 3);
  const uint32_t* storage = a.data();
  HugePageArray<uint32_t> b(std::move(a));
  EXPECT_EQ(a.size(), 0u);
  ASSERT_EQ(b.size(), 5000u);
  EXPECT_EQ(b.data(), storage);
  HugePageArray<uint32_t> c;
  c.assign_zero(10);
  c = std::move(b);
  ASSERT_EQ(c.size(), 5000u);
  size_t wrong = 0;
  for (size_t i = 0; i < c.size(); ++i) wrong += c[i] != uint32_t(i * 3);
  EXPECT_EQ(wrong, 0u);
}

}  // namespace
}  // namespace shadowtiles
