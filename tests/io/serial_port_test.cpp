// SerialPort and PtyPair over a real pseudo-terminal: the kernel's terminal layer sits between
// the two ends, as it would between a board and a USB-serial adapter.
#include "symb/io/serial_port.hpp"

#include <termios.h>

#include <thread>

#include <gtest/gtest.h>

#include "symb/io/frame_codec.hpp"
#include "symb/io/pty_pair.hpp"
#include "symb/kernel/random_stream.hpp"

#include "io_test_support.hpp"

namespace symb::io {
namespace {

using namespace std::chrono_literals;
using symb::testing::eventually;
using testing::read_exactly;
using testing::read_frames;
using testing::Writer;

PtyPair open_pty() {
  auto pair = PtyPair::open("pty");
  if (!pair) ADD_FAILURE() << pair.error();
  return std::move(pair).value();
}

std::vector<std::byte> payload(std::size_t n, std::uint64_t seed) {
  std::vector<std::byte> p(n);
  for (std::size_t i = 0; i < n; ++i) p[i] = static_cast<std::byte>((i + seed) & 0xff);
  return p;
}

// Sends `payloads` as frames from `out` to `in` and checks they all arrive, whole and in order.
void expect_frames_cross(SerialPort& out, SerialPort& in, const std::vector<std::vector<std::byte>>& payloads) {
  std::vector<std::byte> wire;
  for (const auto& p : payloads) encode_frame(p, wire);
  FrameDecoder decoder(1024);
  Writer writer(out, wire);
  auto frames = read_frames(in, decoder, payloads.size());
  EXPECT_EQ(writer.join(), "");
  ASSERT_EQ(frames.size(), payloads.size()) << out.name() << " -> " << in.name();
  for (std::size_t i = 0; i < payloads.size(); ++i) EXPECT_EQ(frames[i], payloads[i]) << "frame " << i;
  EXPECT_EQ(decoder.stats().dropped(), 0u);
  EXPECT_EQ(decoder.stats().frames, payloads.size());
  EXPECT_EQ(decoder.stats().bytes, wire.size());
}

TEST(SerialPort, FramesWithEveryByteValueCrossAPseudoTerminalAt115200) {
  PtyPair pty = open_pty();
  ASSERT_TRUE(pty.master && pty.slave);
  EXPECT_NE(pty.slave_path.find("/dev/pts/"), std::string::npos) << pty.slave_path;
  for (SerialPort* end : {pty.master.get(), pty.slave.get()}) {
    auto baud = end->ioctl("baud", "115200");
    ASSERT_TRUE(baud) << baud.error();
    EXPECT_EQ(*baud, "115200");
    ASSERT_TRUE(end->ioctl("parity", "none"));
    ASSERT_TRUE(end->ioctl("raw", "true"));
    // The terminal itself, read back with tcgetattr, holds the settings.
    auto info = end->ioctl("info");
    ASSERT_TRUE(info) << info.error();
    EXPECT_NE(info->find("ispeed=115200 ospeed=115200 bits=8 parity=none canonical=false echo=false"),
              std::string::npos)
        << *info;
  }
  std::vector<std::vector<std::byte>> payloads;
  for (int round = 0; round < 4; ++round)
    for (std::size_t n : {0u, 1u, 254u, 255u, 256u, 1024u}) payloads.push_back(payload(n, n + round));
  // 256 and 1024 bytes hold every value 0..255, including the ones a cooked terminal would eat or
  // translate: 0x00, XON/XOFF (0x11, 0x13), ^C (0x03), CR (0x0d), LF (0x0a), DEL (0x7f).
  expect_frames_cross(*pty.master, *pty.slave, payloads);
  expect_frames_cross(*pty.slave, *pty.master, payloads);
}

TEST(SerialPort, PlainBytesCrossUntouchedInBothDirectionsAtOnce) {
  PtyPair pty = open_pty();
  std::vector<std::byte> all(std::size_t{256} * 64);
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<std::byte>(i & 0xff);
  Writer a(*pty.master, all);
  Writer b(*pty.slave, all);
  std::vector<std::byte> at_slave;
  std::thread reader([&] { at_slave = read_exactly(*pty.slave, all.size()); });
  const auto at_master = read_exactly(*pty.master, all.size());
  reader.join();
  EXPECT_EQ(a.join(), "");
  EXPECT_EQ(b.join(), "");
  EXPECT_EQ(at_slave, all);
  EXPECT_EQ(at_master, all);
}

// One injected bad segment: what it was, and the cause a fresh decoder gives it on its own.
struct Injected {
  std::size_t segments = 0;
  FrameStats expected;

  void add(std::span<const std::byte> segment_with_delimiters, std::size_t max_payload) {
    FrameDecoder alone(max_payload);
    std::size_t good = 0;
    alone.feed(segment_with_delimiters, [&](std::span<const std::byte>) { ++good; });
    ASSERT_EQ(good, 0u) << "an injected bad segment decoded as a good frame";
    ASSERT_EQ(alone.stats().dropped(), 1u) << "a bad segment must count as exactly one dropped frame";
    ++segments;
    expected.crc_errors += alone.stats().crc_errors;
    expected.truncated += alone.stats().truncated;
    expected.oversized += alone.stats().oversized;
    expected.bad_encoding += alone.stats().bad_encoding;
    expected.bad_version += alone.stats().bad_version;
  }
};

TEST(SerialPort, CorruptedFrameStormDropsExactlyTheInjectedSegments) {
  constexpr std::size_t kMax = 1024;
  constexpr int kValid = 300;
  PtyPair pty = open_pty();
  kernel::RandomStream rnd(20240611, 7);
  std::vector<std::byte> wire;
  std::vector<std::vector<std::byte>> sent;
  Injected bad;
  std::size_t constructed_truncated = 0, constructed_oversized = 0, bursts_with_zero = 0, bursts_without = 0;
  auto random_payload = [&](std::size_t n) {
    std::vector<std::byte> p(n);
    for (auto& b : p) b = static_cast<std::byte>(rnd.below(256));
    return p;
  };
  auto inject = [&](const std::vector<std::byte>& segment) {
    // Framed by zeros on both sides, as it will be on the wire (the frames around it bring them).
    std::vector<std::byte> alone{std::byte{0}};
    alone.insert(alone.end(), segment.begin(), segment.end());
    alone.push_back(std::byte{0});
    bad.add(alone, kMax);
    wire.insert(wire.end(), segment.begin(), segment.end());
  };

  for (int i = 0; i < kValid; ++i) {
    sent.push_back(random_payload(rnd.below(300)));
    encode_frame(sent.back(), wire);
    switch (rnd.below(6)) {
      case 0: {
        // A burst with no zero: one bad segment.
        std::vector<std::byte> g(1 + rnd.below(64));
        for (auto& b : g) b = static_cast<std::byte>(1 + rnd.below(255));
        inject(g);
        ++bursts_without;
        break;
      }
      case 1: {
        // A burst with zeros: each non-empty run between zeros is one bad segment.
        std::vector<std::byte> g(1 + rnd.below(64));
        for (auto& b : g) b = rnd.below(4) == 0 ? std::byte{0} : static_cast<std::byte>(1 + rnd.below(255));
        std::vector<std::byte> run;
        for (std::byte b : g) {
          if (b != std::byte{0}) {
            run.push_back(b);
            continue;
          }
          if (!run.empty()) inject(run);
          run.clear();
          wire.push_back(std::byte{0});
        }
        if (!run.empty()) inject(run);
        ++bursts_with_zero;
        break;
      }
      case 2: {
        // A valid frame cut short, then a delimiter (the cable pulled mid-frame).
        auto f = encode_frame(random_payload(1 + rnd.below(300)));
        const std::size_t keep = 2 + rnd.below(f.size() - 3);  // leading zero + at least one byte
        wire.push_back(std::byte{0});
        inject(std::vector<std::byte>(f.begin() + 1, f.begin() + static_cast<std::ptrdiff_t>(keep)));
        break;
      }
      case 3: {
        // Cut right after its first COBS block when the payload starts with a zero: what is left
        // is well-formed COBS too short to hold version and CRC.
        auto p = random_payload(1 + rnd.below(100));
        p[0] = std::byte{0};
        auto f = encode_frame(p);
        ASSERT_EQ(f[1], std::byte{2});  // version, then the zero ends the first block
        inject({f[1], f[2]});
        ++constructed_truncated;
        break;
      }
      case 4: {
        // A well-formed frame too long for the receiver.
        auto f = encode_frame(random_payload(kMax + 1 + rnd.below(600)));
        inject(std::vector<std::byte>(f.begin() + 1, f.end() - 1));
        ++constructed_oversized;
        break;
      }
      default: break;
    }
  }
  // Ends with a good frame, so every bad segment before it has been counted when it arrives.
  sent.push_back(random_payload(10));
  encode_frame(sent.back(), wire);
  ASSERT_GT(bursts_with_zero, 10u);
  ASSERT_GT(bursts_without, 10u);
  ASSERT_GT(constructed_truncated, 10u);
  ASSERT_GT(constructed_oversized, 10u);

  FrameDecoder decoder(kMax);
  Writer writer(*pty.master, wire, 333);
  auto frames = read_frames(*pty.slave, decoder, sent.size());
  EXPECT_EQ(writer.join(), "");
  ASSERT_EQ(frames.size(), sent.size());
  for (std::size_t i = 0; i < sent.size(); ++i) EXPECT_EQ(frames[i], sent[i]) << "frame " << i;
  const FrameStats& s = decoder.stats();
  EXPECT_EQ(s.dropped(), bad.segments);
  EXPECT_EQ(s.frames, sent.size());
  EXPECT_EQ(s.bytes, wire.size());
  EXPECT_EQ(s.crc_errors, bad.expected.crc_errors);
  EXPECT_EQ(s.truncated, bad.expected.truncated);
  EXPECT_EQ(s.oversized, bad.expected.oversized);
  EXPECT_EQ(s.bad_encoding, bad.expected.bad_encoding);
  EXPECT_EQ(s.bad_version, bad.expected.bad_version);
  EXPECT_GE(s.truncated, constructed_truncated);
  EXPECT_GE(s.oversized, constructed_oversized);
}

TEST(SerialPort, IoctlErrorsNameDeviceAndCommand) {
  PtyPair pty = open_pty();
  SerialPort& port = *pty.slave;

  auto unknown = port.ioctl("bauds", "9600");
  ASSERT_FALSE(unknown);
  EXPECT_NE(unknown.error().find("pty.slave"), std::string::npos) << unknown.error();
  EXPECT_NE(unknown.error().find("'bauds'"), std::string::npos) << unknown.error();
  EXPECT_NE(unknown.error().find("did you mean 'baud'"), std::string::npos) << unknown.error();

  auto not_a_number = port.ioctl("baud", "fast");
  ASSERT_FALSE(not_a_number);
  EXPECT_NE(not_a_number.error().find("baud"), std::string::npos) << not_a_number.error();
  auto too_slow = port.ioctl("baud", "300");
  ASSERT_FALSE(too_slow);
  auto unsupported = port.ioctl("baud", "100000");
  ASSERT_FALSE(unsupported);
  EXPECT_NE(unsupported.error().find("unsupported baud rate 100000"), std::string::npos) << unsupported.error();
  EXPECT_NE(unsupported.error().find("115200"), std::string::npos) << "lists what is supported";
  auto wrong_type = port.ioctl_value("baud", os::ParamValue{std::string("9600")});
  ASSERT_FALSE(wrong_type);
  auto bad_parity = port.ioctl("parity", "mark");
  ASSERT_FALSE(bad_parity);
  EXPECT_NE(bad_parity.error().find("none, even or odd"), std::string::npos) << bad_parity.error();
  EXPECT_FALSE(port.ioctl("raw", "maybe"));
  EXPECT_FALSE(port.ioctl("flush", "now"));
  EXPECT_FALSE(port.ioctl("info", "all"));
  // None of the refused changes stuck.
  EXPECT_EQ(port.settings().baud, 115200);
  EXPECT_EQ(port.settings().parity, Parity::kNone);

  // Good ones change the device itself.
  ASSERT_TRUE(port.ioctl_value("baud", os::ParamValue{std::int64_t{4000000}}));
  // A pseudo-terminal has no parity bit (Linux clears PARENB on it): the setting is kept for the
  // port, and the answer and "info" say that the device did not take it.
  auto even = port.ioctl("parity", "even");
  ASSERT_TRUE(even) << even.error();
  EXPECT_EQ(*even, "even (not kept by the device, which has parity=none)");
  auto info = port.ioctl("info");
  ASSERT_TRUE(info);
  EXPECT_NE(info->find("baud=4000000 parity=even raw=true"), std::string::npos) << *info;
  EXPECT_NE(info->find("device: ispeed=4000000 ospeed=4000000 bits=8 parity=none"), std::string::npos) << *info;
  auto none = port.ioctl("parity", "none");
  ASSERT_TRUE(none);
  EXPECT_EQ(*none, "none");
  auto flushed = port.ioctl("flush");
  ASSERT_TRUE(flushed) << flushed.error();
  // Every supported rate maps to a termios constant the terminal accepts.
  for (int rate : SerialPort::supported_bauds()) {
    auto r = port.ioctl("baud", std::to_string(rate));
    EXPECT_TRUE(r) << rate << ": " << (r ? "" : r.error());
  }
  // "raw false" gives back the terminal's own settings (a fresh pty slave echoes, line by line).
  ASSERT_TRUE(port.ioctl("raw", "false"));
  EXPECT_NE(port.ioctl("info")->find("canonical=true"), std::string::npos) << *port.ioctl("info");
}

TEST(SerialPort, SettingsGivenBeforeOpenApplyAtOpen) {
  PtyPair pty = open_pty();
  SerialPort port("uart1", pty.slave_path);
  EXPECT_FALSE(port.is_open());
  ASSERT_TRUE(port.ioctl("baud", "57600"));
  EXPECT_FALSE(port.ioctl("flush")) << "flush needs an open port";
  EXPECT_NE(port.ioctl("info")->find("open=false baud=57600"), std::string::npos);
  ASSERT_TRUE(port.open());
  EXPECT_NE(port.ioctl("info")->find("ispeed=57600"), std::string::npos) << *port.ioctl("info");
  port.close();
  EXPECT_FALSE(port.is_open());
  ASSERT_TRUE(port.open()) << "a port on a path opens again";
  EXPECT_TRUE(port.is_open());
}

TEST(SerialPort, OpeningWhatIsNotATerminalFailsClearly) {
  SerialPort missing("uart9", "/dev/nonexistent-tty");
  auto st = missing.open();
  ASSERT_FALSE(st);
  EXPECT_NE(st.error().find("/dev/nonexistent-tty"), std::string::npos) << st.error();
  SerialPort null_dev("uart8", "/dev/null");
  st = null_dev.open();
  ASSERT_FALSE(st);
  EXPECT_NE(st.error().find("not a terminal"), std::string::npos) << st.error();
  EXPECT_FALSE(null_dev.is_open());
  std::byte b[4];
  EXPECT_FALSE(null_dev.read_some(b, 1ms));
  EXPECT_FALSE(null_dev.write_all(b));
}

TEST(SerialPort, CloseFromAnotherThreadWakesABlockedReader) {
  PtyPair pty = open_pty();
  testing::expect_close_wakes_blocked_reader(*pty.slave);
}

TEST(SerialPort, TheOtherEndGoingAwayIsEndOfStream) {
  PtyPair pty = open_pty();
  ASSERT_TRUE(pty.master->write_all(as_bytes("bye")));
  EXPECT_EQ(read_exactly(*pty.slave, 3).size(), 3u);
  pty.slave->close();
  pty.slave.reset();
  std::byte buf[8];
  ASSERT_TRUE(eventually([&] { return !pty.master->read_some(buf, 10ms).ok(); }));
  EXPECT_FALSE(pty.master->is_open());
  EXPECT_NE(pty.master->failure().find("end of stream"), std::string::npos) << pty.master->failure();
  EXPECT_FALSE(pty.master->open()) << "an adopted master cannot be reopened";
}

TEST(SerialPort, AWriterStuckOnAPeerThatDoesNotReadTimesOutOrIsWokenByClose) {
  PtyPair pty = open_pty();
  pty.master->set_write_timeout(100ms);
  const std::vector<std::byte> lots(4 << 20, std::byte{0x55});
  auto st = pty.master->write_all(lots);
  ASSERT_FALSE(st) << "4 MiB fit into a pseudo-terminal nobody reads?";
  EXPECT_NE(st.error().find("took no byte for 100 ms"), std::string::npos) << st.error();
  EXPECT_TRUE(pty.master->is_open()) << "a stalled write does not break the line";

  pty.master->set_write_timeout(60s);
  std::atomic<pid_t> tid{0};
  std::string error;
  std::thread writer([&] {
    tid = testing::this_thread_tid();
    auto r = pty.master->write_all(lots);
    if (!r) error = r.error();
  });
  ASSERT_TRUE(eventually([&] { return tid.load() != 0 && testing::thread_sleeping(tid.load()); }));
  const auto t0 = std::chrono::steady_clock::now();
  pty.master->close();
  writer.join();
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 10s);
  EXPECT_NE(error.find("closed"), std::string::npos) << error;
}

}  // namespace
}  // namespace symb::io
