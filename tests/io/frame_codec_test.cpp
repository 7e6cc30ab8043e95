#include "symb/io/frame_codec.hpp"

#include <gtest/gtest.h>

#include "symb/kernel/random_stream.hpp"

namespace symb::io {
namespace {

std::vector<std::byte> bytes(std::initializer_list<int> v) {
  std::vector<std::byte> out;
  for (int x : v) out.push_back(static_cast<std::byte>(x));
  return out;
}

std::vector<std::vector<std::byte>> decode_all(FrameDecoder& d, std::span<const std::byte> in) {
  std::vector<std::vector<std::byte>> out;
  d.feed(in, [&](std::span<const std::byte> f) { out.emplace_back(f.begin(), f.end()); });
  return out;
}

TEST(FrameCodec, CrcMatchesTheStandardCheckValue) {
  const std::string check = "123456789";
  EXPECT_EQ(crc16_ccitt({reinterpret_cast<const std::byte*>(check.data()), check.size()}), 0x29B1);
}

TEST(FrameCodec, RoundTripsEverySizeAndByteValue) {
  kernel::RandomStream rnd(1, 0);
  FrameDecoder d(1024);
  for (std::size_t n : {0u, 1u, 2u, 253u, 254u, 255u, 256u, 508u, 1024u}) {
    std::vector<std::byte> p(n);
    for (std::size_t i = 0; i < n; ++i) p[i] = static_cast<std::byte>(i < 256 ? i : rnd.below(256));
    auto f = encode_frame(p);
    EXPECT_LE(f.size(), max_encoded_size(n));
    for (std::size_t i = 1; i + 1 < f.size(); ++i) ASSERT_NE(f[i], std::byte{0}) << "zero inside frame body";
    auto got = decode_all(d, f);
    ASSERT_EQ(got.size(), 1u) << n;
    EXPECT_EQ(got[0], p) << n;
  }
  EXPECT_EQ(d.stats().dropped(), 0u);
}

TEST(FrameCodec, EachKindOfBadFrameIsCountedAndSkipped) {
  FrameDecoder d(16);
  auto good = encode_frame(bytes({1, 2, 3}));
  std::vector<std::byte> stream;
  auto add = [&](const std::vector<std::byte>& b) { stream.insert(stream.end(), b.begin(), b.end()); };
  add(good);
  auto corrupt = good;
  corrupt[3] ^= std::byte{0x40};
  add(corrupt);                                   // crc
  add(bytes({0, 2, 5, 0}));                       // truncated (one byte body)
  add(encode_frame(std::vector<std::byte>(17)));  // oversized
  add(bytes({0, 9, 1, 2, 0}));                    // COBS code runs past the end
  {
    // A well-formed frame of version 2, COBS-encoded by hand.
    std::vector<std::byte> body = bytes({2, 7});
    const std::uint16_t crc = crc16_ccitt(body);
    body.push_back(std::byte(crc >> 8));
    body.push_back(std::byte(crc & 0xff));
    std::vector<std::byte> f = {std::byte{0}};
    std::size_t code_at = f.size();
    f.push_back(std::byte{1});
    for (std::byte b : body) {
      if (b == std::byte{0}) {
        code_at = f.size();
        f.push_back(std::byte{1});
        continue;
      }
      f.push_back(b);
      f[code_at] = std::byte(static_cast<int>(f[code_at]) + 1);
    }
    f.push_back(std::byte{0});
    add(f);
  }
  add(good);
  auto got = decode_all(d, stream);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[1], bytes({1, 2, 3}));
  const auto& s = d.stats();
  EXPECT_EQ(s.crc_errors, 1u);
  EXPECT_EQ(s.truncated, 1u);
  EXPECT_EQ(s.oversized, 1u);
  EXPECT_EQ(s.bad_encoding, 1u);
  EXPECT_EQ(s.bad_version, 1u);
  EXPECT_EQ(s.dropped(), 5u);
}

TEST(FrameCodec, ResynchronisesAfterGarbageAndSplitDelivery) {
  FrameDecoder d(64);
  auto f = encode_frame(bytes({9, 0, 9}));
  std::vector<std::byte> stream = bytes({7, 7, 7});  // garbage, ended by the frame's leading zero
  stream.insert(stream.end(), f.begin(), f.end());
  std::vector<std::vector<std::byte>> got;
  for (std::byte b : stream)
    d.feed({&b, 1}, [&](std::span<const std::byte> x) { got.emplace_back(x.begin(), x.end()); });
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0], bytes({9, 0, 9}));
  EXPECT_EQ(d.stats().dropped(), 1u);
}

TEST(FrameCodec, EndlessGarbageUsesBoundedMemory) {
  FrameDecoder d(32);
  std::vector<std::byte> junk(100000, std::byte{0x55});
  auto got = decode_all(d, junk);
  EXPECT_TRUE(got.empty());
  junk.assign(1, std::byte{0});
  decode_all(d, junk);
  EXPECT_EQ(d.stats().oversized, 1u);
}

}  // namespace
}  // namespace symb::io
