#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "symb/kernel/random_stream.hpp"
#include "symb/os/syslog.hpp"

namespace symb::os {
namespace {

// What format_seconds replaces: printf's long long, which newlib-nano (the board's) lacks.
std::string printf_seconds(kernel::Time t, int width) {
  char buf[64];
  const std::int64_t us = t.count() / 1000;
  std::snprintf(buf, sizeof buf, "%*lld.%06lld", width, static_cast<long long>(us / 1'000'000),
                static_cast<long long>(us % 1'000'000));
  return buf;
}

TEST(FormatSeconds, EqualsPrintfsLongLongFormatting) {
  kernel::RandomStream r(7);
  for (int i = 0; i < 20000; ++i) {
    // Every magnitude from nanoseconds to centuries, both signs.
    const int shift = static_cast<int>(r.below(62));
    auto ns = static_cast<std::int64_t>(r.next_u64() >> (shift + 1));
    if (r.below(4) == 0) ns = -ns;
    const kernel::Time t{ns};
    for (int width : {0, 6}) ASSERT_EQ(format_seconds(t, width), printf_seconds(t, width)) << ns << " width " << width;
  }
  EXPECT_EQ(format_seconds(kernel::Time{0}, 6), "     0.000000");
  EXPECT_EQ(format_seconds(kernel::Time{12'034'000'999}), "12.034000");
}

}  // namespace
}  // namespace symb::os
