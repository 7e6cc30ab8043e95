#include "symb/kernel/bounded_queue.hpp"

#include <atomic>
#include <chrono>
#include <thread>

#include <gtest/gtest.h>

namespace symb::kernel {
namespace {

using namespace std::chrono_literals;

TEST(BoundedQueue, PoliciesWhenFull) {
  BoundedQueue<int> q(2);
  EXPECT_EQ(q.push(1, FullPolicy::kRefuse), PushResult::kPushed);
  EXPECT_EQ(q.push(2, FullPolicy::kRefuse), PushResult::kPushed);
  EXPECT_EQ(q.push(3, FullPolicy::kRefuse), PushResult::kRefused);
  EXPECT_EQ(q.push(4, FullPolicy::kKeepNewest), PushResult::kOverwrote);
  EXPECT_EQ(q.try_pop(), 2);
  EXPECT_EQ(q.try_pop(), 4);
  EXPECT_EQ(q.try_pop(), std::nullopt);
}

TEST(BoundedQueue, PopTimesOutWhenEmpty) {
  BoundedQueue<int> q(1);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(q.pop_for(20ms), std::nullopt);
  EXPECT_GE(std::chrono::steady_clock::now() - t0, 20ms);
}

TEST(BoundedQueue, PushTimesOutWhenFull) {
  BoundedQueue<int> q(1);
  ASSERT_TRUE(q.push_for(1, 1ms));
  EXPECT_FALSE(q.push_for(2, 10ms));
}

// Waits (up to 10 s) until `n` threads are blocked in `q`: what the next two tests need before
// they push or close, rather than a sleep that a loaded machine may outlast.
bool until_waiting(const BoundedQueue<int>& q, std::size_t n) {
  const auto end = std::chrono::steady_clock::now() + 10s;
  while (q.waiting() < n && std::chrono::steady_clock::now() < end) std::this_thread::sleep_for(1ms);
  return q.waiting() == n;
}

TEST(BoundedQueue, BlockedPopWakesOnPush) {
  BoundedQueue<int> q(1);
  std::atomic<bool> blocked{false};
  std::thread producer([&] {
    blocked = until_waiting(q, 1);
    q.push(42, FullPolicy::kRefuse);
  });
  EXPECT_EQ(q.pop_for(20s), 42);
  producer.join();
  EXPECT_TRUE(blocked);
  EXPECT_EQ(q.waiting(), 0u);
}

TEST(BoundedQueue, CloseWakesWaiters) {
  BoundedQueue<int> empty(1);
  BoundedQueue<int> full(1);
  ASSERT_TRUE(full.push_for(1, 1ms));
  std::thread popper([&] { EXPECT_EQ(empty.pop_for(20s), std::nullopt); });
  std::thread pusher([&] { EXPECT_FALSE(full.push_for(2, 20s)); });
  ASSERT_TRUE(until_waiting(empty, 1));
  ASSERT_TRUE(until_waiting(full, 1));
  const auto t0 = std::chrono::steady_clock::now();
  empty.close();
  full.close();
  popper.join();
  pusher.join();
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 10s);  // woken, not timed out
}

TEST(BoundedQueue, EveryItemCrossesThreadsExactlyOnce) {
  BoundedQueue<int> q(8);
  constexpr int kItems = 20000;
  long long sum = 0;
  std::thread consumer([&] {
    for (int i = 0; i < kItems; ++i) {
      auto v = q.pop_for(10s);
      ASSERT_TRUE(v.has_value());
      sum += *v;
    }
  });
  for (int i = 1; i <= kItems; ++i) ASSERT_TRUE(q.push_for(i, 10s));
  consumer.join();
  EXPECT_EQ(sum, static_cast<long long>(kItems) * (kItems + 1) / 2);
}

}  // namespace
}  // namespace symb::kernel
