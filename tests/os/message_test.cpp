#include "symb/os/message.hpp"

#include <limits>
#include <vector>

#include <gtest/gtest.h>

namespace symb::os {
namespace {

TEST(MessageNumbers, AllFiniteRefusesNaNAndInfinityAnywhere) {
  EXPECT_TRUE(all_finite({}));
  const std::vector<float> ok{0.0f, -1.5f, std::numeric_limits<float>::max(), std::numeric_limits<float>::denorm_min()};
  EXPECT_TRUE(all_finite(ok));
  for (const float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                          -std::numeric_limits<float>::infinity()}) {
    for (std::size_t at = 0; at < ok.size(); ++at) {
      std::vector<float> v = ok;
      v[at] = bad;
      EXPECT_FALSE(all_finite(v)) << "bad value at " << at;
    }
  }
}

// Every count a payload holds: exactly the first n numbers arrive, and nothing on either side of
// them is read or written (the source is a vector of exactly n, so ASan sees any read past it).
TEST(MessageNumbers, CopyNumbersMovesExactlyTheCountWhateverItIs) {
  for (std::size_t n = 0; n <= Payload::kInlineValues; ++n) {
    std::vector<float> from(n);
    for (std::size_t i = 0; i < n; ++i) from[i] = static_cast<float>(i) + 0.5f;
    std::vector<float> to(n + 2, -1.0f);
    copy_numbers(to.data() + 1, from.data(), n);
    EXPECT_EQ(to.front(), -1.0f) << n;
    EXPECT_EQ(to.back(), -1.0f) << n;
    for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(to[i + 1], from[i]) << "n " << n << ", number " << i;
  }
}

TEST(MessageNumbers, APayloadKeepsItsNumbersThroughCopiesAndMoves) {
  for (std::size_t n : {0u, 1u, 2u, 7u, 8u, 9u, 17u, 31u, 32u, 40u}) {
    std::vector<float> v(n);
    for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<float>(3 * i) - 1.0f;
    const Payload p(v);
    const std::size_t kept = std::min<std::size_t>(n, Payload::kInlineValues);
    ASSERT_EQ(p.count, kept);
    Payload copied(p);
    Payload assigned;
    assigned = copied;
    Payload moved(std::move(copied));
    for (const Payload* q : {&assigned, &moved}) {
      ASSERT_EQ(q->numbers().size(), kept) << n;
      for (std::size_t i = 0; i < kept; ++i) EXPECT_EQ(q->numbers()[i], v[i]) << "n " << n << ", number " << i;
    }
  }
}

}  // namespace
}  // namespace symb::os
