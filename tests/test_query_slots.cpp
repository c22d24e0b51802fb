// QuerySlots (server/query_slots.hpp): at most N holders, waiters served first come first served,
// a waiter that times out leaves the line to those behind it.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <thread>
#include <vector>

#include "server/query_slots.hpp"

namespace shadowtiles::server {
namespace {

using namespace std::chrono_literals;

// Waits (bounded) until `slots` has `n` waiters.
bool wait_for_waiters(const QuerySlots& slots, size_t n) {
  for (int i = 0; i < 2000; ++i) {
    if (slots.waiting() == n) return true;
    std::this_thread::sleep_for(1ms);
  }
  return false;
}

TEST(QuerySlots, AtMostTheCountAreHeldAndATimeoutIsAnEmptySlot) {
  QuerySlots slots(2);
  auto a = slots.acquire(0ms);
  auto b = slots.acquire(0ms);
  EXPECT_TRUE(a);
  EXPECT_TRUE(b);
  auto start = std::chrono::steady_clock::now();
  auto c = slots.acquire(30ms);
  EXPECT_FALSE(c);
  EXPECT_GE(std::chrono::steady_clock::now() - start, 30ms);
  EXPECT_EQ(slots.waiting(), 0u) << "a timed-out waiter leaves the queue";
  { auto released = std::move(a); }
  EXPECT_TRUE(slots.acquire(0ms)) << "a released slot is free again";
}

TEST(QuerySlots, WaitersAreGrantedInArrivalOrder) {
  QuerySlots slots(1);
  auto held = std::make_unique<QuerySlots::Slot>(slots.acquire(0ms));
  ASSERT_TRUE(*held);
  constexpr int kWaiters = 8;
  std::mutex order_mutex;
  std::vector<int> order;
  std::vector<std::thread> threads;
  for (int i = 0; i < kWaiters; ++i) {
    threads.emplace_back([&, i] {
      auto slot = slots.acquire(10s);
      EXPECT_TRUE(slot);
      std::lock_guard lock(order_mutex);
      order.push_back(i);
    });
    // Thread i is queued before thread i + 1 starts.
    ASSERT_TRUE(wait_for_waiters(slots, size_t(i) + 1));
  }
  held.reset();  // each holder hands its slot on as it finishes
  for (auto& t : threads) t.join();
  std::vector<int> expected(kWaiters);
  for (int i = 0; i < kWaiters; ++i) expected[size_t(i)] = i;
  EXPECT_EQ(order, expected);
}

TEST(QuerySlots, ATimedOutWaiterLeavesTheLineToThoseBehindIt) {
  QuerySlots slots(1);
  auto held = std::make_unique<QuerySlots::Slot>(slots.acquire(0ms));
  std::atomic<int> first_got{-1}, second_got{-1};
  std::thread first([&] { first_got = bool(slots.acquire(500ms)); });
  ASSERT_TRUE(wait_for_waiters(slots, 1));
  std::thread second([&] { second_got = bool(slots.acquire(10s)); });
  // Both in line (unless the first already gave up: the line is then just the second).
  for (int i = 0; i < 2000 && slots.waiting() < 2 && first_got == -1; ++i) std::this_thread::sleep_for(1ms);
  first.join();  // timed out, gone from the line
  EXPECT_EQ(first_got, 0);
  EXPECT_EQ(slots.waiting(), 1u);
  held.reset();  // wakes the one now first in line
  second.join();
  EXPECT_EQ(second_got, 1);
}

}  // namespace
}  // namespace shadowtiles::server
