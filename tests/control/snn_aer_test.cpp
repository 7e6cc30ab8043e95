// AER spike packets: address packing, the big-endian wire form (round trip bit-identical, malformed
// forms rejected with their byte offset, random truncations and mutations never crash), and
// packets between tasks of a node under virtual time: shared without a copy through hooks, and as
// wire bytes in io::Bytes payloads.
#include <cstring>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "symb/control/snn/aer.hpp"
#include "symb/io/bytes.hpp"
#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"

namespace symb::control::snn {
namespace {

using namespace std::chrono_literals;
using kernel::Time;

std::vector<AerEvent> random_events(std::size_t n, std::uint64_t seed) {
  kernel::RandomStream r(seed);
  std::vector<AerEvent> e(n);
  for (auto& x : e) {
    x.address = static_cast<std::uint32_t>(r.next_u64());
    x.timestamp_us = static_cast<std::uint32_t>(r.next_u64());
  }
  return e;
}

std::vector<std::byte> bytes(std::initializer_list<unsigned> v) {
  std::vector<std::byte> out;
  for (unsigned b : v) out.push_back(static_cast<std::byte>(b));
  return out;
}

// "byte N: ..." with N as given.
void expect_at(const kernel::Result<std::vector<AerEvent>>& r, std::size_t offset) {
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().rfind("byte " + std::to_string(offset) + ": ", 0), 0u) << r.error();
}

TEST(AerAddress, PacksModuleAndNeuronBits) {
  static_assert(kModuleBits + kNeuronBits == 32);
  EXPECT_EQ(aer_address(0, 0), 0u);
  EXPECT_EQ(aer_address(1, 0), 1u << 24);
  EXPECT_EQ(aer_address(3, 5), (3u << 24) | 5u);
  EXPECT_EQ(aer_address(kMaxModule, kMaxNeuronAddress), 0xFFFFFFFFu);
  EXPECT_EQ(kMaxModule, 255u);
  EXPECT_EQ(kMaxNeuronAddress, 0xFFFFFFu);
  // A neuron number too large for its field is cut to the field, never spills into the module.
  EXPECT_EQ(aer_address(2, kMaxNeuronAddress + 1), 2u << 24);
  EXPECT_EQ(aer_module(aer_address(2, kMaxNeuronAddress + 7)), 2u);
  for (std::uint32_t m : {0u, 1u, 17u, kMaxModule})
    for (std::uint32_t n : {0u, 1u, 1000u, kMaxNeuronAddress}) {
      const std::uint32_t a = aer_address(m, n);
      EXPECT_EQ(aer_module(a), m);
      EXPECT_EQ(aer_neuron(a), n);
    }
}

TEST(AerAddress, TimestampIsMicrosecondsWrapping) {
  EXPECT_EQ(aer_timestamp(Time{0ms}), 0u);
  EXPECT_EQ(aer_timestamp(Time{1ms}), 1000u);
  EXPECT_EQ(aer_timestamp(Time{1500us}), 1500u);
  // 2^32 us is about 71.6 minutes: the timestamp wraps.
  const Time wrap = std::chrono::microseconds(std::uint64_t{1} << 32);
  EXPECT_EQ(aer_timestamp(wrap), 0u);
  EXPECT_EQ(aer_timestamp(wrap + 25us), 25u);
}

TEST(AerWire, LayoutIsBigEndianCountThenAddressTimestamp) {
  const std::vector<AerEvent> e{{0x01020304u, 0x05060708u}, {0xA0B0C0D0u, 0x000000FFu}};
  EXPECT_EQ(encode_aer(e), bytes({0, 0, 0, 2, 1, 2, 3, 4, 5, 6, 7, 8, 0xA0, 0xB0, 0xC0, 0xD0, 0, 0, 0, 0xFF}));
  EXPECT_EQ(encode_aer({}), bytes({0, 0, 0, 0}));
}

TEST(AerWire, RoundTripIsBitIdentical) {
  for (std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{100000}}) {
    const auto events = random_events(n, 42 + n);
    const auto wire = encode_aer(events);
    ASSERT_EQ(wire.size(), 4 + 8 * n);
    auto back = decode_aer(wire);
    ASSERT_TRUE(back.ok()) << back.error();
    ASSERT_EQ(back->size(), n);
    EXPECT_TRUE(*back == events) << n << " events";
    EXPECT_EQ(encode_aer(*back), wire);
  }
}

TEST(AerWire, MalformedFormsAreRejectedWithTheirByteOffset) {
  expect_at(decode_aer({}), 0);
  expect_at(decode_aer(bytes({0, 0, 1})), 0);
  // Count 2, one full event and half of the second: the error points at the second event.
  expect_at(decode_aer(bytes({0, 0, 0, 2, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9})), 12);
  // Count 1, no event at all.
  expect_at(decode_aer(bytes({0, 0, 0, 1})), 4);
  // Count 0 but an event follows: the surplus starts at byte 4.
  expect_at(decode_aer(bytes({0, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8})), 4);
  // Count 1, one event and three stray bytes.
  expect_at(decode_aer(bytes({0, 0, 0, 1, 1, 2, 3, 4, 5, 6, 7, 8, 1, 1, 1})), 12);
  // Huge counts are refused before anything is allocated or read.
  auto huge = decode_aer(bytes({0xFF, 0xFF, 0xFF, 0xFF}));
  expect_at(huge, 0);
  EXPECT_NE(huge.error().find("limit"), std::string::npos) << huge.error();
  const std::uint32_t over = kMaxPacketEvents + 1;
  expect_at(decode_aer(bytes({over >> 24, (over >> 16) & 0xFF, (over >> 8) & 0xFF, over & 0xFF})), 0);
}

TEST(AerWire, MaxPacketEventsIsAccepted) {
  const std::vector<AerEvent> events(kMaxPacketEvents, AerEvent{aer_address(1, 2), 3});
  auto back = decode_aer(encode_aer(events));
  ASSERT_TRUE(back.ok()) << back.error();
  EXPECT_EQ(back->size(), kMaxPacketEvents);
}

TEST(AerWire, RandomTruncationsAndMutationsNeverCrash) {
  kernel::RandomStream r(7);
  const auto events = random_events(40, 9);
  const auto wire = encode_aer(events);
  std::size_t rejected = 0;
  for (int i = 0; i < 1000; ++i) {
    // Each case in its own exactly-sized heap buffer, so ASan sees any read past the end.
    std::vector<std::byte> b(wire.begin(), wire.begin() + static_cast<std::ptrdiff_t>(r.below(wire.size() + 1)));
    const auto mutations = r.below(4);
    for (std::uint64_t k = 0; k < mutations && !b.empty(); ++k)
      b[r.below(b.size())] = static_cast<std::byte>(r.below(256));
    auto d = decode_aer(b);
    if (!d) {
      ++rejected;
      EXPECT_EQ(d.error().rfind("byte ", 0), 0u) << d.error();
      continue;
    }
    // Accepted: the length must agree with the count, and encoding gives the same bytes back.
    EXPECT_EQ(b.size(), 4 + 8 * d->size());
    EXPECT_EQ(encode_aer(*d), b);
  }
  EXPECT_GT(rejected, 500u) << "most truncations break the count";
}

// --- packets between tasks ----------------------------------------------------------------------

// Sends the packet (or its wire bytes) queued for each tick.
class SpikeSource : public os::Task {
 public:
  explicit SpikeSource(bool wire) : wire_(wire) {}
  std::vector<std::vector<AerEvent>> packets;

 protected:
  void on_tick() override {
    if (next_ >= packets.size()) return;
    const auto& p = packets[next_++];
    if (wire_)
      send(0, io::bytes_payload(encode_aer(p)));
    else
      send(0, aer_payload(p));
  }

 private:
  bool wire_;
  std::size_t next_ = 0;
};

// Keeps every packet it receives (as the blob itself, or decoded from wire bytes).
class SpikeSink : public os::Task {
 public:
  std::vector<std::shared_ptr<const os::Blob>> blobs() const {
    std::lock_guard lock(mu_);
    return blobs_;
  }
  std::vector<std::vector<AerEvent>> decoded() const {
    std::lock_guard lock(mu_);
    return decoded_;
  }

 protected:
  void on_message(const os::Message& m) override {
    std::lock_guard lock(mu_);
    if (aer_of(m) != nullptr) blobs_.push_back(m.payload.blob);
    if (const io::Bytes* b = io::bytes_of(m)) {
      auto d = decode_aer(b->data);
      EXPECT_TRUE(d.ok()) << (d ? "" : d.error());
      if (d) decoded_.push_back(std::move(*d));
    }
  }

 private:
  mutable std::mutex mu_;
  std::vector<std::shared_ptr<const os::Blob>> blobs_;
  std::vector<std::vector<AerEvent>> decoded_;
};

struct SpikeRig {
  kernel::VirtualTimeExecutor ex;
  os::Node node{ex, {"n", 1}};
  SpikeSource* source = nullptr;
  SpikeSink* a = nullptr;
  SpikeSink* b = nullptr;

  explicit SpikeRig(bool wire, std::size_t sends) {
    auto s = std::make_unique<SpikeSource>(wire);
    source = s.get();
    for (std::size_t k = 0; k < sends; ++k) {
      auto e = random_events(50 + 300 * k, 100 + k);
      for (std::size_t i = 0; i < e.size(); ++i) e[i].timestamp_us = static_cast<std::uint32_t>(1000 * k + i);
      source->packets.push_back(std::move(e));
    }
    const auto tx = *node.create("spikes", std::move(s), {.period = 10ms});
    auto ra = std::make_unique<SpikeSink>();
    a = ra.get();
    auto rb = std::make_unique<SpikeSink>();
    b = rb.get();
    const auto ia = *node.create("a", std::move(ra), {.queue_capacity = 64});
    const auto ib = *node.create("b", std::move(rb), {.queue_capacity = 64});
    EXPECT_TRUE(node.hook(tx, ia).ok());
    EXPECT_TRUE(node.hook(tx, ib).ok());
  }
};

TEST(AerPackets, HookedReceiversShareOneBlobWithIdenticalEvents) {
  SpikeRig rig(false, 5);
  rig.ex.run_until(Time{100ms});
  const auto ga = rig.a->blobs();
  const auto gb = rig.b->blobs();
  ASSERT_EQ(ga.size(), 5u);
  ASSERT_EQ(gb.size(), 5u);
  for (std::size_t k = 0; k < ga.size(); ++k) {
    EXPECT_EQ(ga[k].get(), gb[k].get()) << "send " << k << ": one blob, no copy";
    const AerPacket* pa = os::blob_as<AerPacket>(ga[k].get());
    const AerPacket* pb = os::blob_as<AerPacket>(gb[k].get());
    ASSERT_NE(pa, nullptr);
    ASSERT_NE(pb, nullptr);
    ASSERT_EQ(pa->events.size(), rig.source->packets[k].size());
    EXPECT_EQ(std::memcmp(pa->events.data(), rig.source->packets[k].data(), pa->events.size() * sizeof(AerEvent)), 0);
    EXPECT_TRUE(pb->events == rig.source->packets[k]);
    if (k > 0) {
      EXPECT_NE(ga[k].get(), ga[k - 1].get()) << "every send its own packet";
    }
  }
}

TEST(AerPackets, WireBytesBetweenTasksDecodeToTheSentEvents) {
  SpikeRig rig(true, 4);
  rig.ex.run_until(Time{100ms});
  for (const SpikeSink* sink : {rig.a, rig.b}) {
    const auto got = sink->decoded();
    ASSERT_EQ(got.size(), 4u);
    for (std::size_t k = 0; k < got.size(); ++k) EXPECT_TRUE(got[k] == rig.source->packets[k]) << "send " << k;
  }
}

TEST(AerPackets, AerOfIgnoresOtherPayloads) {
  os::Message m;
  EXPECT_EQ(aer_of(m), nullptr);
  m.payload = os::Payload{1.0f, 2.0f};
  EXPECT_EQ(aer_of(m), nullptr);
  m.payload = io::text_payload("spikes");
  EXPECT_EQ(aer_of(m), nullptr);
  m.payload = aer_payload({{aer_address(1, 2), 3}});
  ASSERT_NE(aer_of(m), nullptr);
  EXPECT_EQ(aer_of(m)->events.size(), 1u);
}

}  // namespace
}  // namespace symb::control::snn
