#include "symb/io/stream.hpp"

#include <thread>

#include <gtest/gtest.h>

#include "symb/io/loopback_stream.hpp"

namespace symb::io {
namespace {

using namespace std::chrono_literals;

TEST(Stream, OperatorsConvertBothWays) {
  auto [a, b] = make_loopback_pair("lb");
  *a << 42 << ' ' << -1.5 << ' ' << "word" << ' ' << true << ' ' << 0.1f << '\n';
  ASSERT_TRUE(*a);
  int i = 0;
  double d = 0;
  std::string w;
  bool flag = false;
  float f = 0;
  *b >> i >> d >> w >> flag >> f;
  ASSERT_TRUE(*b);
  EXPECT_EQ(i, 42);
  EXPECT_EQ(d, -1.5);
  EXPECT_EQ(w, "word");
  EXPECT_TRUE(flag);
  EXPECT_EQ(f, 0.1f);
}

TEST(Stream, BadConversionSetsFailAndKeepsTheTarget) {
  auto [a, b] = make_loopback_pair("lb");
  b->set_read_timeout(50ms);
  *a << "notanumber 7\n";
  int i = 5;
  *b >> i;
  EXPECT_TRUE(b->fail());
  EXPECT_EQ(i, 5);
  b->clear_fail();
  *b >> i;
  EXPECT_EQ(i, 7);
  *b >> i;  // nothing more: times out
  EXPECT_TRUE(b->fail());
}

TEST(Stream, ReadLineKeepsPartialLinesAcrossTimeouts) {
  auto [a, b] = make_loopback_pair("lb");
  *a << "hel";
  auto first = b->read_line(20ms);
  ASSERT_TRUE(first);
  EXPECT_FALSE(first->has_value());
  *a << "lo\r\nworld\n";
  EXPECT_EQ(b->read_line(1s)->value(), "hello");
  EXPECT_EQ(b->read_line(1s)->value(), "world");
  *a << std::string(100, 'x') << '\n';
  EXPECT_EQ(b->read_line(1s, 10)->value(), std::string(10, 'x'));
}

TEST(Stream, CloseIsSeenByThePeerAndWakesAReader) {
  auto [a, b] = make_loopback_pair("lb");
  IOStream* end_a = a.get();  // clang 14 cannot capture a structured binding
  std::thread closer([end_a] {
    std::this_thread::sleep_for(20ms);
    end_a->close();
  });
  std::byte buf[8];
  const auto t0 = std::chrono::steady_clock::now();
  auto r = b->read_some(buf, 10s);
  closer.join();
  EXPECT_FALSE(r);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 5s);
  EXPECT_FALSE(b->is_open());
  EXPECT_FALSE(a->write_all(as_bytes("x")));
}

TEST(Stream, BytesAfterCloseAreStillDelivered) {
  auto [a, b] = make_loopback_pair("lb");
  ASSERT_TRUE(a->write_all(as_bytes("last words")));
  a->close();
  std::byte buf[32];
  auto r = b->read_some(buf, 1s);
  ASSERT_TRUE(r);
  EXPECT_EQ(*r, 10u);
  EXPECT_FALSE(b->read_some(buf, 1s));
}

}  // namespace
}  // namespace symb::io
