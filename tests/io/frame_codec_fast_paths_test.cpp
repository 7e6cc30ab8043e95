// The frame codec's fast paths (table CRC, carry-less multiply folding with SSE and AVX-512,
// memchr and AVX-512 COBS) against plain reference code written the slow, obvious way: any
// length, alignment, starting CRC and zero density must give the same bytes. Which SIMD path
// runs depends on the CPU; on this project's reference machine all of them do.
#include <gtest/gtest.h>

#include "symb/io/frame_codec.hpp"
#include "symb/kernel/random_stream.hpp"

namespace symb::io {
namespace {

std::uint16_t crc_reference(std::span<const std::byte> data, std::uint16_t crc) {
  for (std::byte b : data) {
    crc ^= static_cast<std::uint16_t>(static_cast<unsigned>(b) << 8);
    for (int i = 0; i < 8; ++i)
      crc =
          (crc & 0x8000) != 0 ? static_cast<std::uint16_t>((crc << 1) ^ 0x1021) : static_cast<std::uint16_t>(crc << 1);
  }
  return crc;
}

// COBS one byte at a time, as the codec's first version did it.
std::vector<std::byte> encode_reference(std::span<const std::byte> payload) {
  std::vector<std::byte> body{std::byte{kFrameVersion}};
  body.insert(body.end(), payload.begin(), payload.end());
  const std::uint16_t crc = crc_reference(body, 0xFFFF);
  body.push_back(static_cast<std::byte>(crc >> 8));
  body.push_back(static_cast<std::byte>(crc & 0xff));
  std::vector<std::byte> out{std::byte{0}};
  std::size_t code_at = out.size();
  out.push_back(std::byte{1});
  for (std::byte b : body) {
    if (b != std::byte{0}) {
      out.push_back(b);
      out[code_at] = static_cast<std::byte>(static_cast<unsigned>(out[code_at]) + 1);
    }
    if (b == std::byte{0} || out[code_at] == std::byte{0xff}) {
      code_at = out.size();
      out.push_back(std::byte{1});
    }
  }
  out.push_back(std::byte{0});
  return out;
}

std::vector<std::byte> random_bytes(kernel::RandomStream& rnd, std::size_t n, std::uint64_t zero_one_in) {
  std::vector<std::byte> v(n);
  for (auto& b : v) b = rnd.below(zero_one_in) == 0 ? std::byte{0} : static_cast<std::byte>(1 + rnd.below(255));
  return v;
}

TEST(FrameCodecFastPaths, CrcMatchesTheBitwiseDefinitionAtEveryLengthAndAlignment) {
  kernel::RandomStream rnd(11, 0);
  std::vector<std::byte> buf = random_bytes(rnd, 2200, 256);
  for (std::size_t n = 0; n <= 2100; n += (n < 600 ? 1 : 7)) {
    for (std::size_t offset : {0u, 1u, 7u, 33u}) {
      const auto init = static_cast<std::uint16_t>(rnd.below(65536));
      const std::span<const std::byte> data(buf.data() + offset, n);
      ASSERT_EQ(crc16_ccitt(data, init), crc_reference(data, init)) << "length " << n << " offset " << offset;
    }
  }
  // Split anywhere, a running CRC gives the same as one pass.
  const std::span<const std::byte> all(buf.data(), 1500);
  for (std::size_t cut : {0u, 1u, 63u, 64u, 255u, 256u, 1000u, 1500u})
    EXPECT_EQ(crc16_ccitt(all.subspan(cut), crc16_ccitt(all.first(cut))), crc16_ccitt(all)) << cut;
}

TEST(FrameCodecFastPaths, EncodingMatchesTheByteAtATimeReference) {
  kernel::RandomStream rnd(12, 0);
  FrameDecoder decoder(4096);
  for (std::uint64_t zeros : {1u, 2u, 8u, 64u, 300u, 100000u}) {
    for (std::size_t n : {0u,   1u,   15u,  16u,  63u,  64u,  191u, 192u,  193u,  252u,
                          253u, 254u, 255u, 256u, 507u, 508u, 509u, 1000u, 1024u, 4096u}) {
      const auto p = random_bytes(rnd, n, zeros);
      std::vector<std::byte> out{std::byte{0x42}};  // appends after what is there
      encode_frame(p, out);
      const auto ref = encode_reference(p);
      ASSERT_EQ(out.size(), ref.size() + 1) << "size " << n << ", zero one in " << zeros;
      ASSERT_TRUE(std::equal(ref.begin(), ref.end(), out.begin() + 1)) << "size " << n << ", zero one in " << zeros;
      std::size_t got = 0;
      decoder.feed(ref, [&](std::span<const std::byte> f) {
        ++got;
        EXPECT_TRUE(std::equal(f.begin(), f.end(), p.begin(), p.end()));
      });
      EXPECT_EQ(got, 1u);
    }
  }
  EXPECT_EQ(decoder.stats().dropped(), 0u);
}

}  // namespace
}  // namespace symb::io
