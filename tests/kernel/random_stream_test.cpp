#include "symb/kernel/random_stream.hpp"

#include <cmath>

#include <gtest/gtest.h>

namespace symb::kernel {
namespace {

TEST(RandomStream, SameSeedAndStreamSameNumbers) {
  RandomStream a(42, 7), b(42, 7);
  for (int i = 0; i < 1000; ++i) ASSERT_EQ(a.next_u64(), b.next_u64());
}

TEST(RandomStream, StreamsAreIndependent) {
  RandomStream a(42, 1), b(42, 2);
  int equal = 0;
  for (int i = 0; i < 1000; ++i) equal += a.next_u64() == b.next_u64();
  EXPECT_EQ(equal, 0);
}

// Golden values pin the generator: a change here changes every recorded run.
TEST(RandomStream, GoldenSequence) {
  RandomStream r(1, 0);
  EXPECT_EQ(r.next_u64(), 0x3752bdaf106afaecULL);
  EXPECT_EQ(r.next_u64(), 0x4441cbc0ffebc80fULL);
  EXPECT_EQ(r.next_u64(), 0x2a4eaa9ffeb08f42ULL);
  RandomStream n(1, 0);
  EXPECT_DOUBLE_EQ(n.normal(), -0.85726776982502517);
}

TEST(RandomStream, UniformAndNormalMoments) {
  RandomStream r(3, 0);
  constexpr int kN = 200000;
  double su = 0, sn = 0, sn2 = 0;
  for (int i = 0; i < kN; ++i) {
    const double u = r.uniform();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    su += u;
    const double n = r.normal();
    sn += n;
    sn2 += n * n;
  }
  EXPECT_NEAR(su / kN, 0.5, 0.01);
  EXPECT_NEAR(sn / kN, 0.0, 0.01);
  EXPECT_NEAR(sn2 / kN, 1.0, 0.02);
}

TEST(RandomStream, BelowIsInRangeAndCoversIt) {
  RandomStream r(5, 0);
  int seen[7] = {};
  for (int i = 0; i < 7000; ++i) {
    const auto v = r.below(7);
    ASSERT_LT(v, 7u);
    ++seen[v];
  }
  for (int c : seen) EXPECT_GT(c, 800);
}

}  // namespace
}  // namespace symb::kernel
