// The pieces the Cortex-M board (board/, docs/board.md) supplies for what its toolchain lacks,
// checked on the host against what they replace.
#include <charconv>
#include <cmath>
#include <cstring>
#include <string>

#include <gtest/gtest.h>

#include "symb/kernel/random_stream.hpp"

#include "port/parse_chars.hpp"
#include "port/shortest_chars.hpp"

namespace symb::kernel {
namespace {

TEST(BoardPort, MultiplyWithout128BitIntegersEqualsInt128) {
  RandomStream r(11);
  for (int i = 0; i < 100000; ++i) {
    const std::uint64_t a = r.next_u64() >> r.below(64), b = r.next_u64() >> r.below(64);
    std::uint64_t high = 0;
    const std::uint64_t low = multiply_64x64(a, b, high);
    const unsigned __int128 m = static_cast<unsigned __int128>(a) * b;
    ASSERT_EQ(low, static_cast<std::uint64_t>(m));
    ASSERT_EQ(high, static_cast<std::uint64_t>(m >> 64));
  }
}

template <class T>
std::string std_text(T v) {
  char buf[64];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  return {buf, r.ptr};
}
template <class T>
std::string board_text(T v) {
  char buf[64];
  auto r = board::shortest_chars(buf, buf + sizeof buf, v);
  return {buf, r.ptr};
}

TEST(BoardPort, ShortestCharsWritesWhatToCharsWrites) {
  RandomStream r(12);
  const double specials[] = {
      0.0,    -0.0,   1.0, 0.1,    1e20, 1e21, 123456.0,           1e-7, 5e-324, 1.7976931348623157e308, 300.0,
      -300.0, 4505.0, 0.3, 2.5e-5, 1e16, 1e15, 12345678901234567.0};
  for (double d : specials) {
    EXPECT_EQ(board_text(d), std_text(d)) << d;
    EXPECT_EQ(board_text(static_cast<float>(d)), std_text(static_cast<float>(d))) << d;
  }
  EXPECT_EQ(board_text(std::nan("")), std_text(std::nan("")));
  EXPECT_EQ(board_text(-INFINITY), std_text(-INFINITY));
  for (int i = 0; i < 5000; ++i) {
    const std::uint64_t bits = r.next_u64();
    double d;
    std::memcpy(&d, &bits, sizeof d);
    if (std::isnan(d)) continue;
    ASSERT_EQ(board_text(d), std_text(d)) << bits;
    const auto fbits = static_cast<std::uint32_t>(bits);
    float f;
    std::memcpy(&f, &fbits, sizeof f);
    if (std::isnan(f)) continue;
    ASSERT_EQ(board_text(f), std_text(f)) << fbits;
    // Values a robot prints: a few digits, moderate exponents.
    const double g = std::round(r.uniform(-5000, 5000) * 1000) / 1000;
    ASSERT_EQ(board_text(g), std_text(g)) << g;
  }
}

template <class T>
void expect_same_parse(const std::string& s) {
  T a = T(-7), b = T(-7);
  const auto ra = std::from_chars(s.data(), s.data() + s.size(), a);
  const auto rb = board::parse_chars(s.data(), s.data() + s.size(), b);
  EXPECT_EQ(ra.ec, rb.ec) << s;
  EXPECT_EQ(ra.ptr - s.data(), rb.ptr - s.data()) << s;
  if (std::isnan(a))
    EXPECT_TRUE(std::isnan(b)) << s;
  else
    EXPECT_EQ(a, b) << s;
}

TEST(BoardPort, ParseCharsReadsWhatFromCharsReads) {
  const char* texts[] = {"0",
                         "-0",
                         "1",
                         "1.5",
                         ".5",
                         "5.",
                         "-.5e3",
                         "1e5",
                         "1e",
                         "1e+",
                         "1e+x",
                         "1E-3",
                         "+1",
                         " 1",
                         "abc",
                         "",
                         "-",
                         ".",
                         "inf",
                         "-INF",
                         "infinity",
                         "infinit",
                         "nan",
                         "NaN(123)",
                         "nan(",
                         "1e400",
                         "-1e400",
                         "1e-400",
                         "4.9e-324",
                         "0x10",
                         "12abc",
                         "3.14159265358979323846",
                         "1.0000000000000000000001",
                         "300",
                         "1200",
                         "2s"};
  for (const char* t : texts) {
    expect_same_parse<double>(t);
    expect_same_parse<float>(t);
  }
  RandomStream r(13);
  for (int i = 0; i < 20000; ++i) {
    const std::uint64_t bits = r.next_u64();
    double d;
    std::memcpy(&d, &bits, sizeof d);
    if (std::isnan(d)) continue;
    const std::string s = std_text(d);
    expect_same_parse<double>(s);
    expect_same_parse<float>(s);
  }
}

}  // namespace
}  // namespace symb::kernel
