// The DDS bus in one process (both ends of each remote hook here, through Cyclone DDS's own
// delivery) and against a raw Cyclone DDS writer that speaks garbage, floods or skips serials.
// The tests across processes are in tests/apps/serve_test.cpp.
#include "symb/io/dds/dds_bus.hpp"

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <thread>

#include <dds/dds.h>
#include <gtest/gtest.h>

#include "symb/kernel/thread_executor.hpp"
#include "symb/os/node.hpp"

#include "HookFrame.h"

// Debian's Cyclone DDS is not built for ThreadSanitizer: its threads hand network buffers to each
// other through its own atomics, which TSan cannot see, so it reports races on those buffers
// between two of Cyclone's threads (its receive thread and its delivery queue, its garbage
// collector and its sender). Only races with Cyclone's socket calls on a stack are suppressed:
// our listeners and proxies never touch its buffers, so a race of ours is still reported.
#if defined(__SANITIZE_THREAD__)
extern "C" const char* __tsan_default_suppressions() { return "race:ddsrt_sendmsg\nrace:ddsrt_recvmsg\n"; }
#endif

namespace symb::io {
namespace {

using namespace std::chrono_literals;

// Sends every message it is handed on, port kept: the test posts into it, its hooks carry it.
class DdsEcho final : public os::Task {
 protected:
  void on_message(const os::Message& m) override { send(m.port, m.payload); }
};

class DdsCount final : public os::Task {
 public:
  std::atomic<std::uint64_t> count{0};
  std::atomic<float> last{0};

 protected:
  void on_message(const os::Message& m) override {
    if (m.payload.count > 0) last.store(m.payload.values[0]);
    count.fetch_add(1);
  }
};

// A domain and a topic prefix of this test run's own, so parallel ctest runs do not meet.
DdsBusOptions own_bus(std::string_view test) {
  static std::atomic<int> serial{0};
  DdsBusOptions o;
  o.domain = 10 + static_cast<std::uint32_t>(::getpid()) % 200;
  o.prefix = std::string(test) + "_" + std::to_string(::getpid()) + "_" + std::to_string(serial++);
  o.lease = 300ms;
  return o;
}

template <class F>
bool eventually(F done, std::chrono::milliseconds limit = 5000ms) {
  const auto until = std::chrono::steady_clock::now() + limit;
  while (!done()) {
    if (std::chrono::steady_clock::now() > until) return false;
    std::this_thread::sleep_for(1ms);
  }
  return true;
}

struct DdsPair {
  kernel::ThreadExecutor ex;
  os::Node r1{ex, {"r1"}};
  os::Node r2{ex, {"r2"}};
  DdsCount* count = nullptr;
  os::TaskId src, sink;
  DdsPair(std::size_t sink_queue = 64) {
    src = *r1.create("src", std::make_unique<DdsEcho>(), {.queue_capacity = 256});
    auto c = std::make_unique<DdsCount>();
    count = c.get();
    sink = *r2.create("sink", std::move(c), {.queue_capacity = sink_queue});
  }
};

TEST(DdsBus, CarriesAHookBetweenNodesWithExactBooks) {
  DdsPair p;
  auto bus = DdsBus::create({&p.r1, &p.r2}, own_bus("exact")).value();
  const auto id = bus->hook("r1/src", "r2/sink", {.port = 3}).value();
  ASSERT_TRUE(bus->wait_linked(5s));
  constexpr int kMessages = 500;
  const auto message = [](os::Port port, float v) {
    os::Message m;
    m.port = port;
    m.payload = os::Payload({v, 2.0f});
    return m;
  };
  for (int i = 0; i < kMessages; ++i) {
    ASSERT_TRUE(p.r1.post(p.src, message(3, float(i))).ok());
    if (i % 50 == 49) {
      ASSERT_TRUE(eventually([&] { return p.count->count.load() == std::uint64_t(i + 1); }));
    }
  }
  ASSERT_TRUE(p.r1.post(p.src, message(4, 1.0f)).ok());  // not this hook's port
  ASSERT_TRUE(eventually([&] { return p.count->count.load() == kMessages; }));
  EXPECT_EQ(p.count->last.load(), float(kMessages - 1));
  const auto hooks = bus->hooks();
  ASSERT_EQ(hooks.size(), 1u);
  const RemoteHookInfo& h = hooks[0];
  EXPECT_EQ(h.id, id);
  EXPECT_EQ(h.state, LinkState::kUp);
  EXPECT_EQ(h.books.attempted, std::uint64_t(kMessages));
  EXPECT_EQ(h.books.delivered, std::uint64_t(kMessages));
  EXPECT_EQ(h.books.dropped(), 0u);
  EXPECT_EQ(h.books.in_flight, 0u);
  EXPECT_TRUE(h.books.closes());
  const DdsBusCounts c = bus->counts();
  EXPECT_EQ(c.written, std::uint64_t(kMessages));
  EXPECT_EQ(c.received, std::uint64_t(kMessages));
  EXPECT_EQ(c.lost, 0u);
  EXPECT_EQ(c.garbage(), 0u);
  EXPECT_EQ(bus->topic("r1/src", "r2/sink", 3), "rt/" + bus->options().prefix + "/r1/src/to/r2/sink/port3");
}

TEST(DdsBus, RefusesBadHooksWithTheirNames) {
  DdsPair p;
  auto bus = DdsBus::create({&p.r1, &p.r2}, own_bus("refuse")).value();
  EXPECT_EQ(bus->hook("r1src", "r2/sink").error(),
            "remote hook r1src -> r2/sink: 'r1src' is not of the form node/task");
  EXPECT_EQ(bus->hook("r1/nope", "r2/sink").error(), "remote hook r1/nope -> r2/sink: no task 'nope' on r1");
  EXPECT_EQ(bus->hook("r7/a", "r8/b").error(),
            "remote hook r7/a -> r8/b: neither end is on this process (its nodes: r1, r2)");
  ASSERT_TRUE(bus->hook("r1/src", "r2/sink").ok());
  EXPECT_NE(bus->hook("r1/src", "r2/sink").error().find("already hooked"), std::string::npos);
  EXPECT_FALSE(DdsBus::create({&p.r1}, {.domain = 233}).ok());
}

// A raw Cyclone DDS writer on a hook's topic, as a foreign peer would write.
struct DdsRawPeer {
  dds_entity_t participant, topic, writer;
  DdsRawPeer(const DdsBusOptions& o, const std::string& name) {
    participant = dds_create_participant(o.domain, nullptr, nullptr);
    topic = dds_create_topic(participant, &symb_msg_dds__HookFrame__desc, name.c_str(), nullptr, nullptr);
    dds_qos_t* qos = dds_create_qos();
    dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
    dds_qset_history(qos, DDS_HISTORY_KEEP_ALL, 0);
    dds_qset_liveliness(qos, DDS_LIVELINESS_AUTOMATIC, DDS_MSECS(300));
    writer = dds_create_writer(participant, topic, qos, nullptr);
    dds_delete_qos(qos);
  }
  ~DdsRawPeer() { dds_delete(participant); }
  void write(const char* hook, std::uint32_t serial, std::uint16_t port, std::uint32_t count) {
    float values[40] = {};
    values[0] = float(serial);
    symb_msg_dds__HookFrame_ s{};
    s.hook = const_cast<char*>(hook);
    s.origin = 77;
    s.serial = serial;
    s.port = port;
    s.values._length = s.values._maximum = count;
    s.values._buffer = values;
    ASSERT_EQ(dds_write(writer, &s), DDS_RETCODE_OK);
  }
  bool matched() const {
    dds_publication_matched_status_t st{};
    return dds_get_publication_matched_status(writer, &st) == DDS_RETCODE_OK && st.current_count > 0;
  }
};

TEST(DdsBus, CountsAndNamesGarbageAndLossAndKeepsWhatItAccepted) {
  DdsPair p;
  const DdsBusOptions o = own_bus("garbage");
  auto bus = DdsBus::create({&p.r2}, o).value();  // the receiving end only: the sender is foreign
  ASSERT_TRUE(bus->hook("r1/src", "r2/sink", {.port = 3}).ok());
  DdsRawPeer peer(o, bus->topic("r1/src", "r2/sink", 3));
  ASSERT_TRUE(eventually([&] { return peer.matched(); }));
  const char* key = "r1/src>r2/sink:3";
  peer.write(key, 0, 3, 2);               // good
  peer.write("r9/x>r2/sink:3", 1, 3, 2);  // another hook's name
  peer.write(key, 1, 3, 40);              // too many numbers
  peer.write(key, 1, 5, 2);               // a port the hook does not carry
  peer.write(key, 1, 3, 2);               // good
  peer.write(key, 1, 3, 2);               // the same serial again
  peer.write(key, 5, 3, 2);               // good, after a gap of 3 (serials 2, 3, 4)
  ASSERT_TRUE(eventually([&] { return p.count->count.load() == 3 && bus->counts().garbage() == 4; }));
  const DdsBusCounts c = bus->counts();
  EXPECT_EQ(c.received, 3u);
  EXPECT_EQ(c.unknown_hook, 1u);
  EXPECT_EQ(c.bad_size, 1u);
  EXPECT_EQ(c.bad_port, 1u);
  EXPECT_EQ(c.out_of_order, 1u);
  EXPECT_EQ(c.lost, 3u);
  EXPECT_EQ(p.count->last.load(), 5.0f);
  // Each cause is in the receiver's log, with what was wrong.
  std::string log;
  for (const auto& line : p.r2.log().since(0)) log += line.text + "\n";
  EXPECT_NE(log.find("40 numbers, more than 32"), std::string::npos) << log;
  EXPECT_NE(log.find("port 5, the hook carries port 3 only"), std::string::npos) << log;
  EXPECT_NE(log.find("names hook 'r9/x>r2/sink:3'"), std::string::npos) << log;
  EXPECT_NE(log.find("3 message(s) lost in transit"), std::string::npos) << log;
}

TEST(DdsBus, AFloodIsRefusedAndCountedAtTheReceiverNotLost) {
  DdsPair p(/*sink_queue=*/8);
  const DdsBusOptions o = own_bus("flood");
  auto bus = DdsBus::create({&p.r2}, o).value();
  ASSERT_TRUE(bus->hook("r1/src", "r2/sink").ok());
  ASSERT_TRUE(p.r2.suspend(p.sink).ok());  // a receiver that does not keep up
  DdsRawPeer peer(o, bus->topic("r1/src", "r2/sink", -1));
  ASSERT_TRUE(eventually([&] { return peer.matched(); }));
  constexpr std::uint32_t kFlood = 2000;
  for (std::uint32_t i = 0; i < kFlood; ++i) peer.write("r1/src>r2/sink", i, 0, 1);
  ASSERT_TRUE(eventually([&] { return bus->counts().received == kFlood; }));
  ASSERT_TRUE(eventually([&] {
    const auto h = bus->hooks()[0];
    return h.books.in_flight <= 8 + 64 && h.medium.posted + h.medium.refused == kFlood;
  }));
  ASSERT_TRUE(p.r2.resume(p.sink).ok());
  ASSERT_TRUE(eventually([&] { return bus->hooks()[0].books.in_flight == 0; }));
  const auto h = bus->hooks()[0];
  // Everything taken from DDS is either delivered or counted as refused at the receiver.
  EXPECT_EQ(h.books.delivered + h.books.dropped(HookDrop::kReceiver), std::uint64_t(kFlood));
  EXPECT_GT(h.books.dropped(HookDrop::kReceiver), 0u);
  EXPECT_EQ(p.count->count.load(), h.books.delivered);
  EXPECT_EQ(bus->counts().lost, 0u);
}

TEST(DdsBus, ASenderThatStopsIsReportedAndTheHookGoesDown) {
  DdsPair p;
  const DdsBusOptions o = own_bus("lease");
  auto bus = DdsBus::create({&p.r2}, o).value();
  ASSERT_TRUE(bus->hook("r1/src", "r2/sink").ok());
  {
    DdsRawPeer peer(o, bus->topic("r1/src", "r2/sink", -1));
    ASSERT_TRUE(eventually([&] { return peer.matched(); }));
    peer.write("r1/src>r2/sink", 0, 0, 1);
    ASSERT_TRUE(eventually([&] { return p.count->count.load() == 1; }));
    EXPECT_EQ(bus->hooks()[0].state, LinkState::kUp);
  }  // the peer leaves (its writer deleted): counted as left, the hook down
  ASSERT_TRUE(eventually([&] { return bus->counts().peers_left == 1; }));
  EXPECT_EQ(bus->hooks()[0].state, LinkState::kDown);
  EXPECT_EQ(bus->counts().peers_lost, 0u);  // a clean leave is not a loss
}

}  // namespace
}  // namespace symb::io
