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

}  // namespace
}  // namespace symb::os
