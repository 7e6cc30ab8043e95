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
  const std::string quoted = shortened(flood, kQuotedReference);
  EXPECT_EQ(quoted.size(), kQuotedReference + 3);
  EXPECT_EQ(quoted.substr(kQuotedReference), "...");
}

}  // namespace
}  // namespace symb::kernel
