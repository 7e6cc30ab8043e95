#include "symb/kernel/ring_buffer.hpp"

#include <gtest/gtest.h>

namespace symb::kernel {
namespace {

TEST(RingBuffer, FifoOrderAcrossWrapAround) {
  RingBuffer<int> rb(3);
  for (int round = 0; round < 5; ++round) {
    rb.push(round * 10 + 1);
    rb.push(round * 10 + 2);
    EXPECT_EQ(rb.take(), round * 10 + 1);
    EXPECT_EQ(rb.take(), round * 10 + 2);
  }
  EXPECT_TRUE(rb.empty());
}

TEST(RingBuffer, OverwriteDropsOldestAndReportsIt) {
  RingBuffer<int> rb(2);
  EXPECT_FALSE(rb.push_overwrite(1));
  EXPECT_FALSE(rb.push_overwrite(2));
  EXPECT_TRUE(rb.full());
  EXPECT_TRUE(rb.push_overwrite(3));
  EXPECT_EQ(rb.size(), 2u);
  EXPECT_EQ(rb.take(), 2);
  EXPECT_EQ(rb.take(), 3);
}

TEST(RingBuffer, ZeroCapacityBecomesOne) {
  RingBuffer<int> rb(0);
  EXPECT_EQ(rb.capacity(), 1u);
}

}  // namespace
}  // namespace symb::kernel
