// CanSocket on a virtual CAN bus (vcan). Where the kernel or the network namespace has no
// SocketCAN, or no vcan interface can be made, the bus tests are skipped with the reason: a
// simulated bus here would test nothing about SocketCAN.
#include "symb/io/can_socket.hpp"

#include <cstdlib>

#include <gtest/gtest.h>

#include "io_test_support.hpp"

namespace symb::io {
namespace {

using namespace std::chrono_literals;

constexpr const char* kBus = "vcan0";

// Ok when kBus can be used; tries to create it (needs iproute2, the vcan module and
// CAP_NET_ADMIN) when only the interface is missing.
kernel::Status bus_ready() {
  auto st = can_available(kBus);
  if (st || st.error().find("SocketCAN is not available") != std::string::npos) return st;
  (void)std::system("ip link add dev vcan0 type vcan >/dev/null 2>&1; ip link set up vcan0 >/dev/null 2>&1");
  return can_available(kBus);
}

#define SKIP_WITHOUT_VCAN()                                                                      \
  do {                                                                                           \
    auto ready = bus_ready();                                                                    \
    if (!ready) GTEST_SKIP() << "no usable virtual CAN bus '" << kBus << "': " << ready.error(); \
  } while (false)

TEST(CanSocket, UnusableInterfacesAreClearErrors) {
  auto missing = can_available("nosuchcan7");
  ASSERT_FALSE(missing);
  EXPECT_TRUE(missing.error().find("SocketCAN is not available") != std::string::npos ||
              missing.error().find("no network interface 'nosuchcan7'") != std::string::npos)
      << missing.error();
  EXPECT_FALSE(can_available(""));
  EXPECT_FALSE(can_available(std::string(40, 'x')));
  CanSocket s("nosuchcan7");
  EXPECT_FALSE(s.open());
  EXPECT_FALSE(s.is_open());
  std::byte buf[8];
  EXPECT_FALSE(s.read_some(buf, 1ms));
  EXPECT_FALSE(s.write_all(buf));
  // The ioctls check their arguments without a bus.
  EXPECT_TRUE(s.ioctl("tx_id", "0x123") || s.ioctl("tx_id", "291"));
  EXPECT_FALSE(s.ioctl("tx_id", "-5"));
  EXPECT_FALSE(s.ioctl("rx_id", "600000000"));
  auto typo = s.ioctl("txid", "1");
  ASSERT_FALSE(typo);
  EXPECT_NE(typo.error().find("did you mean 'tx_id'"), std::string::npos) << typo.error();
  EXPECT_NE(s.ioctl("info")->find("interface=nosuchcan7"), std::string::npos);
  CanFrame too_long;
  too_long.size = 9;
  EXPECT_FALSE(s.write_frame(too_long));
}

TEST(CanSocket, FramesCrossAVirtualBus) {
  SKIP_WITHOUT_VCAN();
  CanSocket a(kBus), b(kBus);
  ASSERT_TRUE(a.open());
  ASSERT_TRUE(b.open());
  CanFrame f;
  f.id = 0x123;
  f.size = 5;
  for (std::uint8_t i = 0; i < 5; ++i) f.data[i] = static_cast<std::byte>(0xA0 + i);
  ASSERT_TRUE(a.write_frame(f));
  CanFrame ext;
  ext.id = 0x1ABCDEF;
  ext.extended = true;
  ext.size = 8;
  ASSERT_TRUE(a.write_frame(ext));
  CanFrame bad_id;
  bad_id.id = 0x800;  // needs the extended format
  auto st = a.write_frame(bad_id);
  ASSERT_FALSE(st);
  EXPECT_NE(st.error().find("0x800"), std::string::npos) << st.error();

  auto got = b.read_frame(testing::kDeadline);
  ASSERT_TRUE(got && *got) << (got ? "timed out" : got.error());
  EXPECT_EQ((*got)->id, 0x123u);
  EXPECT_FALSE((*got)->extended);
  ASSERT_EQ((*got)->size, 5);
  EXPECT_EQ((*got)->data[4], std::byte{0xA4});
  auto got_ext = b.read_frame(testing::kDeadline);
  ASSERT_TRUE(got_ext && *got_ext);
  EXPECT_EQ((*got_ext)->id, 0x1ABCDEFu);
  EXPECT_TRUE((*got_ext)->extended);
}

TEST(CanSocket, ByteStreamOverCanKeepsOrderAndFiltersById) {
  SKIP_WITHOUT_VCAN();
  CanSocket a(kBus, 0x321), b(kBus, 0x100, 0x321);
  ASSERT_TRUE(a.open());
  ASSERT_TRUE(b.open());
  CanSocket noise(kBus, 0x555);
  ASSERT_TRUE(noise.open());
  std::vector<std::byte> bytes(1000);
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<std::byte>(i & 0xff);
  ASSERT_TRUE(noise.write_all(as_bytes("not for b")));
  testing::Writer w(a, bytes, 37);
  EXPECT_EQ(testing::read_exactly(b, bytes.size()), bytes);
  EXPECT_EQ(w.join(), "");
}

}  // namespace
}  // namespace symb::io
