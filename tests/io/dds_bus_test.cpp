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

#include "symb/io/bytes.hpp"
#include "symb/kernel/thread_executor.hpp"
#include "symb/os/node.hpp"

#include "HookFrame.h"
#include "support/eventually.hpp"

namespace symb::io {
namespace {

using namespace std::chrono_literals;
using os::TaskId;
using symb::testing::eventually;
using symb::testing::kEventuallyLimit;

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

// An echo that counts the messages it handled on a thread other than its own (the one its
// on_start ran on): the DDS listener's, when it was idle (kernel::RunWakesHere).
class DdsEchoNotingThread final : public os::Task {
 public:
  std::atomic<std::thread::id> own{};
  std::atomic<int> handled{0}, elsewhere{0};

 protected:
  void on_start() override { own.store(std::this_thread::get_id()); }
  void on_message(const os::Message& m) override {
    if (std::this_thread::get_id() != own.load()) elsewhere.fetch_add(1);
    handled.fetch_add(1);
    send(m.port, m.payload);
  }
};

os::Message numbers_on(os::Port port, os::Payload payload) {
  os::Message m;
  m.port = port;
  m.payload = std::move(payload);
  return m;
}

// A domain and a topic prefix of this test run's own, so parallel ctest runs do not meet.
DdsBusOptions own_bus(std::string_view test) {
  static std::atomic<int> serial{0};
  DdsBusOptions o;
  o.domain = 10 + static_cast<std::uint32_t>(::getpid()) % 200;
  o.prefix = std::string(test) + "_" + std::to_string(::getpid()) + "_" + std::to_string(serial++);
  o.lease = 300ms;
  return o;
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
  ASSERT_TRUE(bus->wait_linked(kEventuallyLimit));
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

// A message crosses with no proxy task: the sender's hook writes to DDS (a hook to a sink, named
// dds_to.<id>), and the listener sends as the stand-in dds_from.<id> straight into the receiver's
// queue through a local hook that keeps the remote hook's priority, queue policy and suppression.
TEST(DdsBus, TheReceiversPriorityPolicyAndSuppressionApplyOnTheDirectPath) {
  DdsPair p(/*sink_queue=*/8);
  const TaskId boss = *p.r2.create("boss", std::make_unique<DdsEcho>());
  ASSERT_TRUE(p.r2.hook(boss, p.sink, {.priority = 5, .suppress_window = 60s}));
  auto bus = DdsBus::create({&p.r1, &p.r2}, own_bus("rules")).value();
  ASSERT_TRUE(bus->hook("r1/src", "r2/sink", {.priority = 2, .policy = os::QueuePolicy::kRefuse}).ok());
  ASSERT_TRUE(bus->wait_linked(kEventuallyLimit));
  // The ends as the nodes list them: no proxy task on either side.
  EXPECT_FALSE(p.r1.find("dds_to.1").has_value());
  bool sink_end = false, stand_in = false;
  for (const os::HookInfo& h : p.r1.hooks())
    if (h.sender_name == "src" && h.receiver_name == "dds_to.1" && !h.receiver.valid()) sink_end = true;
  for (const os::HookInfo& h : p.r2.hooks())
    if (h.sender_name == "dds_from.1" && h.receiver == p.sink && h.options.priority == 2 &&
        h.options.policy == os::QueuePolicy::kRefuse)
      stand_in = true;
  EXPECT_TRUE(sink_end);
  EXPECT_TRUE(stand_in);
  const auto books = [&] { return bus->hooks().at(0).books; };
  const auto send = [&](int n) {
    for (int i = 0; i < n; ++i) ASSERT_TRUE(p.r1.post(p.src, numbers_on(0, os::Payload({float(i)}))));
  };

  // Refuse: a receiver that does not run keeps 8 and refuses the rest, counted at the receiver.
  ASSERT_TRUE(p.r2.suspend(p.sink).ok());
  send(20);
  // Settled when the books also close: a message its sender's hook has counted may not have
  // reached the bus's writer yet (the sink is called after the sender's lock is released).
  ASSERT_TRUE(eventually([&] {
    const RemoteHookBooks now = books();
    return now.attempted == 20 && now.in_flight == 8 && now.closes();
  }));
  EXPECT_EQ(books().dropped(HookDrop::kReceiver), 12u);
  EXPECT_TRUE(books().closes());
  ASSERT_TRUE(p.r2.resume(p.sink).ok());
  ASSERT_TRUE(eventually([&] { return p.count->count.load() == 8; }));

  // A higher-priority delivery into the receiver opens a window that drops the remote hook's.
  ASSERT_TRUE(p.r2.post(boss, numbers_on(0, os::Payload({-1.0f}))));
  ASSERT_TRUE(eventually([&] { return p.count->count.load() == 9; }));
  send(5);
  ASSERT_TRUE(eventually([&] {
    const RemoteHookBooks now = books();
    return now.attempted == 25 && now.in_flight == 0 && now.closes();
  }));
  const RemoteHookBooks b = books();
  EXPECT_EQ(b.delivered, 8u);
  EXPECT_EQ(b.dropped(HookDrop::kReceiver), 12u + 5u);
  EXPECT_TRUE(b.closes());
  EXPECT_EQ(p.count->count.load(), 9u);
  EXPECT_EQ(p.count->last.load(), -1.0f);
  EXPECT_EQ(bus->counts().written, 25u);  // the receiver's rules drop after DDS, never before
  EXPECT_EQ(bus->counts().received, 25u);
}

// The sender's side of the hook: its port filter and an inhibition apply before DDS, a blob is
// refused, and each is counted in the books.
TEST(DdsBus, TheSendersPortInhibitionAndBlobsAreCountedBeforeDds) {
  DdsPair p;
  auto bus = DdsBus::create({&p.r1, &p.r2}, own_bus("sender")).value();
  ASSERT_TRUE(bus->hook("r1/src", "r2/sink", {.port = 1}).ok());
  ASSERT_TRUE(bus->wait_linked(kEventuallyLimit));
  const auto books = [&] { return bus->hooks().at(0).books; };
  ASSERT_TRUE(p.r1.post(p.src, numbers_on(1, os::Payload({1.0f}))));
  ASSERT_TRUE(p.r1.post(p.src, numbers_on(2, os::Payload({2.0f}))));  // another port
  ASSERT_TRUE(eventually([&] { return p.count->count.load() == 1; }));
  ASSERT_TRUE(p.r1.post(p.src, numbers_on(1, text_payload("a blob"))));
  ASSERT_TRUE(eventually([&] { return books().dropped(HookDrop::kBlob) == 1; }));
  ASSERT_TRUE(p.r1.inhibit(p.src, {}, 60s));
  ASSERT_TRUE(p.r1.post(p.src, numbers_on(1, os::Payload({3.0f}))));
  ASSERT_TRUE(eventually([&] { return books().attempted == 3; }));
  const RemoteHookBooks b = books();
  EXPECT_EQ(b.delivered, 1u);
  EXPECT_EQ(b.dropped(HookDrop::kBlob), 1u);
  EXPECT_EQ(b.dropped(HookDrop::kSender), 1u);  // inhibited
  EXPECT_EQ(b.in_flight, 0u);
  EXPECT_TRUE(b.closes());
  EXPECT_EQ(bus->counts().written, 1u);
}

// A flood from a peer into a receiver whose hook refuses: the receiver's bounded queue takes what
// it can, the rest is refused and counted; nothing taken from DDS goes unaccounted.
TEST(DdsBus, AFloodIntoARefusingHookIsRefusedByTheReceiversQueueAndCounted) {
  DdsPair p(/*sink_queue=*/8);
  const DdsBusOptions o = own_bus("refuse_flood");
  auto bus = DdsBus::create({&p.r2}, o).value();
  ASSERT_TRUE(bus->hook("r1/src", "r2/sink", {.policy = os::QueuePolicy::kRefuse}).ok());
  ASSERT_TRUE(p.r2.suspend(p.sink).ok());
  DdsRawPeer peer(o, bus->topic("r1/src", "r2/sink", -1));
  ASSERT_TRUE(eventually([&] { return peer.matched(); }));
  constexpr std::uint32_t kFlood = 2000;
  for (std::uint32_t i = 0; i < kFlood; ++i) peer.write("r1/src>r2/sink", i, 0, 1);
  ASSERT_TRUE(eventually([&] { return bus->hooks()[0].medium.posted == kFlood; }));
  const auto full = bus->hooks()[0];
  EXPECT_EQ(full.books.in_flight, 8u);
  EXPECT_EQ(full.books.dropped(HookDrop::kReceiver), kFlood - 8);
  ASSERT_TRUE(p.r2.resume(p.sink).ok());
  ASSERT_TRUE(eventually([&] { return p.count->count.load() == 8 && bus->hooks()[0].books.in_flight == 0; }));
  EXPECT_EQ(p.count->last.load(), 7.0f);  // a refusing queue keeps the oldest
  const auto h = bus->hooks()[0];
  EXPECT_EQ(h.books.delivered + h.books.dropped(HookDrop::kReceiver), std::uint64_t(kFlood));
  EXPECT_EQ(bus->counts().received, kFlood);
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

TEST(DdsBus, AnIdleReceiverHandlesOnTheListenersThreadAndMayAnswerOverDdsFromThere) {
  kernel::ThreadExecutor ex;
  os::Node r1{ex, {"r1"}};
  os::Node r2{ex, {"r2"}};
  const TaskId src = *r1.create("src", std::make_unique<DdsEcho>(), {});
  auto c = std::make_unique<DdsCount>();
  DdsCount& count = *c;
  const TaskId sink = *r1.create("sink", std::move(c), {});
  auto e = std::make_unique<DdsEchoNotingThread>();
  DdsEchoNotingThread& echo = *e;
  ASSERT_TRUE(r2.create("echo", std::move(e), {}).ok());
  (void)sink;
  auto bus = DdsBus::create({&r1, &r2}, own_bus("guest")).value();
  ASSERT_TRUE(bus->hook("r1/src", "r2/echo").ok());
  ASSERT_TRUE(bus->hook("r2/echo", "r1/sink").ok());
  ASSERT_TRUE(bus->wait_linked(kEventuallyLimit));
  constexpr int kMessages = 20;
  for (int i = 0; i < kMessages; ++i) {
    ASSERT_TRUE(r1.post(src, numbers_on(0, os::Payload({float(i)}))).ok());
    ASSERT_TRUE(eventually([&] { return count.count.load() == std::uint64_t(i + 1); }));
    std::this_thread::sleep_for(2ms);  // every task idle again
  }
  EXPECT_EQ(count.last.load(), float(kMessages - 1));
  EXPECT_EQ(echo.handled.load(), kMessages);
  // Each message finds `echo` idle; a few may still find it finishing the one before.
  EXPECT_GE(echo.elsewhere.load(), kMessages / 2);
  for (const RemoteHookInfo& h : bus->hooks()) {
    EXPECT_EQ(h.books.delivered, std::uint64_t(kMessages)) << h.sender << " -> " << h.receiver;
    EXPECT_TRUE(h.books.closes());
  }
}

}  // namespace
}  // namespace symb::io
