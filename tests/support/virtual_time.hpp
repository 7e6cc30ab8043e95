// Instants of a virtual-time test, in milliseconds from the executor's epoch: ms(250).
#pragma once

#include <chrono>

#include "symb/kernel/time.hpp"

namespace symb::test_support {

inline kernel::Time ms(long long n) { return std::chrono::milliseconds(n); }

}  // namespace symb::test_support
