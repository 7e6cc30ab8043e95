#include "symb/kernel/source_text.hpp"

#include <string>

#include <gtest/gtest.h>

namespace symb::kernel {
namespace {

TEST(SourceText, ShortenedKeepsTextUpToItsLimitAndCutsLongerText) {
  EXPECT_EQ(shortened("", 4), "");
  EXPECT_EQ(shortened("abcd", 4), "abcd");
  EXPECT_EQ(shortened("abcde", 4), "abcd...");
  const std::string flood(100000, 'x');
  const std::string quoted = shortened(flood, 120);
  EXPECT_EQ(quoted.size(), 123u);
  EXPECT_EQ(quoted.substr(120), "...");
}

}  // namespace
}  // namespace symb::kernel
