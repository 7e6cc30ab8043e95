// Remote hooks' generic pieces: the hook frame round-trips every count of numbers at the size its
// formula states, bad frames are refused with the byte offset, and the two proxies over an
// in-memory medium (which corrupts some frames) keep the books of a remote hook exact: attempted
// == delivered + dropped + in flight after every handler, with decode errors and blobs counted.
#include "symb/io/remote_hook.hpp"

#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "symb/io/bytes.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"

namespace symb::io {
namespace {

using namespace std::chrono_literals;

TEST(RemoteHookFrame, RoundTripsAtTheStatedSize) {
  FrameDecoder decoder(256);
  std::vector<std::byte> wire;
  for (std::size_t n = 0; n <= os::Payload::kInlineValues; ++n) {
    HookFrame f{.hook = 7,
                .sequence = 0xA0B0C0D0U + static_cast<std::uint32_t>(n),
                .time = kernel::Time{-123456789},
                .port = static_cast<os::Port>(65530 + n),
                .payload = {}};
    f.payload.count = static_cast<std::uint8_t>(n);
    for (std::size_t i = 0; i < n; ++i) f.payload.values[i] = static_cast<float>(i) * 0.25f - 3.0f;
    encode_hook_frame(f, wire);
    ASSERT_EQ(wire.size(), hook_frame_wire_bytes(n)) << n;
    ASSERT_EQ(wire.size(), 26 + 4 * n) << n;
    int frames = 0;
    decoder.feed(wire, [&](std::span<const std::byte> payload) {
      ++frames;
      auto back = parse_hook_frame(payload);
      ASSERT_TRUE(back.ok()) << back.error();
      EXPECT_EQ(back->hook, f.hook);
      EXPECT_EQ(back->sequence, f.sequence);
      EXPECT_EQ(back->time, f.time);
      EXPECT_EQ(back->port, f.port);
      ASSERT_EQ(back->payload.count, n);
      for (std::size_t i = 0; i < n; ++i) EXPECT_EQ(back->payload.values[i], f.payload.values[i]);
    });
    EXPECT_EQ(frames, 1);
  }
}

TEST(RemoteHookFrame, RefusesBadPayloadsWithTheOffset) {
  std::vector<std::byte> p(kHookFrameHeader, std::byte{0});
  auto r = parse_hook_frame(std::span(p).first(10));
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("shorter than its 20-byte header"), std::string::npos) << r.error();
  r = parse_hook_frame(p);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("byte 0"), std::string::npos) << r.error();
  p[0] = std::byte{'H'};
  p[19] = std::byte{40};
  r = parse_hook_frame(p);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("byte 19 counts 40"), std::string::npos) << r.error();
  p[19] = std::byte{2};
  r = parse_hook_frame(p);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("2 numbers make 28"), std::string::npos) << r.error();
  p.resize(28);
  EXPECT_TRUE(parse_hook_frame(p).ok());
}

// Carries frames at once from the outbound proxy to the inbound one; every third frame gets a
// byte flipped (the CRC must catch it).
class MemoryMedium final : public HookMedium {
 public:
  os::Node* to = nullptr;
  os::TaskId inbound;
  MediumBooks books;

  void transmit(std::uint32_t, std::span<const std::byte> frame, std::size_t) override {
    ++books.handed;
    std::vector<std::byte> copy(frame.begin(), frame.end());
    if (books.handed % 3 == 0) copy[copy.size() / 2] ^= std::byte{0x10};
    os::Message m;
    m.payload = bytes_payload(copy);
    if (to->post(inbound, m, os::QueuePolicy::kRefuse).ok())
      ++books.posted;
    else
      ++books.refused;
  }
  void refuse(std::uint32_t, HookDrop cause) override {
    if (cause == HookDrop::kBlob) {
      ++books.handed;
      ++books.blob;
    }
    if (cause == HookDrop::kDecode) ++books.decode;
  }
};

class RhSource final : public os::Task {
 protected:
  void on_tick() override {
    if (++n_ % 10 == 0)
      send(1, text_payload("a blob"));
    else
      send(1, {static_cast<float>(n_), 2.0f});
  }

 private:
  int n_ = 0;
};

class RhSink final : public os::Task {
 public:
  std::vector<float> seen;
  std::vector<os::Port> ports;

 protected:
  void on_message(const os::Message& m) override {
    seen.push_back(m.numbers()[0]);
    ports.push_back(m.port);
  }
};

TEST(RemoteHookProxies, BooksCloseAfterEveryHandlerWithDecodeErrorsAndBlobsCounted) {
  kernel::VirtualTimeExecutor ex;
  os::Node a(ex, {.name = "a", .seed = 1});
  os::Node b(ex, {.name = "b", .seed = 2});
  MemoryMedium medium;
  auto src = a.create("src", std::make_unique<RhSource>(), {.period = 1ms});
  auto out = a.create("out", std::make_unique<OutboundProxy>(medium, 9), {.queue_capacity = 4});
  auto sink_task = std::make_unique<RhSink>();
  RhSink* sink = sink_task.get();
  auto rcv = b.create("rcv", std::move(sink_task));
  auto in = b.create("in", std::make_unique<InboundProxy>(medium, 9));
  ASSERT_TRUE(src.ok() && out.ok() && rcv.ok() && in.ok());
  medium.to = &b;
  medium.inbound = *in;
  auto in_hook = b.hook(*in, *rcv);
  auto out_hook = a.hook(*src, *out);
  ASSERT_TRUE(in_hook.ok() && out_hook.ok());
  auto traffic = [](const os::Node& n, os::HookId id) {
    for (const auto& h : n.hooks())
      if (h.id == id) return h.accounting;
    return os::HookTraffic{};
  };
  RemoteHookBooks books;
  for (int i = 0; i < 3000; ++i) {
    ex.run_for(100us);
    books = remote_hook_books(traffic(a, *out_hook), medium.books, traffic(b, *in_hook));
    ASSERT_TRUE(books.closes()) << "after " << i;
  }
  EXPECT_EQ(books.attempted, 300U);
  EXPECT_EQ(books.dropped(HookDrop::kBlob), 30U);
  // Of the 270 frames, every third had a byte flipped.
  EXPECT_EQ(books.dropped(HookDrop::kDecode), 90U);
  EXPECT_EQ(books.delivered, 180U);
  EXPECT_EQ(books.in_flight, 0U);
  ASSERT_EQ(sink->seen.size(), 180U);
  for (std::size_t k = 1; k < sink->seen.size(); ++k) EXPECT_LT(sink->seen[k - 1], sink->seen[k]);
  for (const os::Port p : sink->ports) EXPECT_EQ(p, 1);
}

}  // namespace
}  // namespace symb::io
