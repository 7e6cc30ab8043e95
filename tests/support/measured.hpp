// near_measured: a figure a test measured once, wrote down beside its bound and a doc quotes (a
// distance, a share of a baseline's fitness). The run must stay within `margin` of it either way:
// below, it is a regression; above, the doc no longer tells the truth. Either way re-measure, and
// update the test's figure and the doc's together.
#pragma once

#include <cmath>

#include <gtest/gtest.h>

namespace symb::testing {

inline ::testing::AssertionResult near_measured(double value, double measured, double margin) {
  if (std::abs(value - measured) <= margin) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << value << " is more than " << margin << " from the measured " << measured
                                       << " (" << (value < measured ? "a regression" : "better than documented")
                                       << ": re-measure, then update the test's figure and its doc)";
}

}  // namespace symb::testing
