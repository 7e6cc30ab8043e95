#include <gtest/gtest.h>

#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"

#include "test_tasks.hpp"

namespace symb::os {
namespace {

using namespace std::chrono_literals;
using kernel::Time;
using testing::Collector;
using testing::Emitter;
using testing::Scripted;

struct Fixture : ::testing::Test {
  kernel::VirtualTimeExecutor ex;
  Node node{ex, {"n", 1}};

  std::pair<TaskId, Collector*> collector(const std::string& name, TaskOptions o = {}) {
    auto c = std::make_unique<Collector>();
    Collector* p = c.get();
    return {*node.create(name, std::move(c), o), p};
  }
  // A task that sends `values` on `port` whenever the test calls fire().
  struct Sender {
    TaskId id;
    Scripted* task;
    void fire(Port port, std::initializer_list<float> values) { task->send(port, values); }
  };
  Sender sender(const std::string& name) {
    auto s = std::make_unique<Scripted>();
    Scripted* p = s.get();
    return {*node.create(name, std::move(s)), p};
  }
};

using Hooks = Fixture;

TEST_F(Hooks, OneSendReachesEveryHookedTask) {
  auto [a, ca] = collector("a");
  auto [b, cb] = collector("b");
  auto [c, cc] = collector("c");
  auto tx = *node.create("tx", std::make_unique<Emitter>(7), {.period = 10ms});
  ASSERT_TRUE(node.hook(tx, a));
  ASSERT_TRUE(node.hook(tx, b));
  ex.run_until(Time{30ms});
  EXPECT_EQ(ca->count(), 3u);
  EXPECT_EQ(cb->count(), 3u);
  EXPECT_EQ(cc->count(), 0u);
  auto got = ca->received();
  EXPECT_EQ(got[1].time, Time{20ms});
  EXPECT_EQ(got[1].source, tx);
  EXPECT_EQ(got[1].port, 7);
  EXPECT_EQ(got[1].values, std::vector<float>{2.0f});
  EXPECT_EQ(node.info(tx)->sent, 3u);
  EXPECT_EQ(node.info(a)->traffic.delivered, 3u);
}

TEST_F(Hooks, UnhookAndDisableStopDelivery) {
  auto [a, ca] = collector("a");
  auto tx = *node.create("tx", std::make_unique<Emitter>(), {.period = 10ms});
  auto h = *node.hook(tx, a);
  ex.run_until(Time{20ms});
  ASSERT_TRUE(node.set_hook_enabled(h, false));
  ex.run_until(Time{40ms});
  ASSERT_TRUE(node.set_hook_enabled(h, true));
  ex.run_until(Time{50ms});
  ASSERT_TRUE(node.unhook(h));
  EXPECT_FALSE(node.unhook(h));
  ex.run_until(Time{80ms});
  EXPECT_EQ(ca->count(), 3u);  // at 10, 20 and 50 ms
  EXPECT_EQ(node.traffic().attempted, 3u);
}

TEST_F(Hooks, PortFilter) {
  auto [a, ca] = collector("a");
  auto s = sender("s");
  ex.run_until_idle();
  ASSERT_TRUE(node.hook(s.id, a, {.port = 2}));
  s.fire(1, {1});
  s.fire(2, {2});
  ex.run_until_idle();
  ASSERT_EQ(ca->count(), 1u);
  EXPECT_EQ(ca->received()[0].port, 2);
  EXPECT_FALSE(node.hook(s.id, a, {.port = 70000}));
}

TEST_F(Hooks, FullQueuePoliciesAreCountedExactly) {
  auto [keep, ck] = collector("keep", {.queue_capacity = 2});
  auto [refuse, cr] = collector("refuse", {.queue_capacity = 2});
  auto s = sender("s");
  ex.run_until_idle();
  ASSERT_TRUE(node.hook(s.id, keep, {.policy = QueuePolicy::kKeepNewest}));
  ASSERT_TRUE(node.hook(s.id, refuse, {.policy = QueuePolicy::kRefuse}));
  // Five sends inside one handler: nobody drains in between.
  for (float v = 1; v <= 5; ++v) s.fire(0, {v});
  ex.run_until_idle();
  auto values = [](Collector* c) {
    std::vector<float> v;
    for (auto& r : c->received()) v.push_back(r.values[0]);
    return v;
  };
  EXPECT_EQ(values(ck), (std::vector<float>{4, 5}));
  EXPECT_EQ(values(cr), (std::vector<float>{1, 2}));
  auto k = node.info(keep)->traffic;
  auto r = node.info(refuse)->traffic;
  EXPECT_EQ(k.attempted, 5u);
  EXPECT_EQ(k.overwritten, 3u);
  EXPECT_EQ(r.refused, 3u);
  EXPECT_EQ(r.delivered + r.dropped(), r.attempted);
}

TEST_F(Hooks, HigherPriorityHooksDeliverFirst) {
  std::vector<std::string> order;
  auto make = [&](const std::string& name) {
    auto t = std::make_unique<Scripted>();
    t->message = [&order, name](Scripted&, const Message&) { order.push_back(name); };
    return *node.create(name, std::move(t));
  };
  auto lo = make("lo"), hi = make("hi"), mid = make("mid");
  auto s = sender("s");
  ex.run_until_idle();
  ASSERT_TRUE(node.hook(s.id, lo, {.priority = 1}));
  ASSERT_TRUE(node.hook(s.id, hi, {.priority = 9}));
  ASSERT_TRUE(node.hook(s.id, mid, {.priority = 5}));
  s.fire(0, {});
  ex.run_until_idle();
  EXPECT_EQ(order, (std::vector<std::string>{"hi", "mid", "lo"}));
}

struct Image final : Blob {
  static constexpr std::uint32_t kKind = 0x494d47;
  std::uint32_t kind() const override { return kKind; }
  std::vector<float> pixels = std::vector<float>(100000, 0.5f);
};

TEST_F(Hooks, LargePayloadsAreSharedNotCopied) {
  std::vector<const Blob*> seen;
  auto make = [&](const std::string& name) {
    auto t = std::make_unique<Scripted>();
    t->message = [&seen](Scripted&, const Message& m) {
      ASSERT_NE(blob_as<Image>(m.payload.blob.get()), nullptr);
      seen.push_back(m.payload.blob.get());
    };
    return *node.create(name, std::move(t));
  };
  auto a = make("a"), b = make("b");
  auto s = sender("s");
  ex.run_until_idle();
  ASSERT_TRUE(node.hook(s.id, a));
  ASSERT_TRUE(node.hook(s.id, b));
  auto img = std::make_shared<const Image>();
  s.task->send(0, Payload(img));
  ex.run_until_idle();
  ASSERT_EQ(seen.size(), 2u);
  EXPECT_EQ(seen[0], img.get());
  EXPECT_EQ(seen[1], img.get());
  EXPECT_EQ(img.use_count(), 1);  // no receiver keeps a copy alive after handling
}

TEST_F(Hooks, InlinePayloadCarriesThirtyTwoNumbers) {
  auto [a, ca] = collector("a");
  auto s = sender("s");
  ex.run_until_idle();
  ASSERT_TRUE(node.hook(s.id, a));
  std::vector<float> v(40);
  for (int i = 0; i < 40; ++i) v[i] = static_cast<float>(i);
  s.task->send(0, std::span<const float>(v));
  ex.run_until_idle();
  auto got = ca->received().at(0).values;
  ASSERT_EQ(got.size(), Payload::kInlineValues);
  EXPECT_EQ(got.back(), 31.0f);
}

// Suppression: a delivery through a hook with a window blocks lower-priority hooks into the same
// receiver for exactly [t, t + window).
TEST_F(Hooks, SuppressionWindowIsExactInVirtualTime) {
  auto [rx, col] = collector("rx", {.queue_capacity = 64});
  auto low = sender("low");
  auto high = sender("high");
  auto other = sender("other");
  ex.run_until_idle();
  ASSERT_TRUE(node.hook(low.id, rx, {.priority = 1}));
  ASSERT_TRUE(node.hook(high.id, rx, {.priority = 5, .suppress_window = 100ms}));
  ASSERT_TRUE(node.hook(other.id, rx, {.priority = 5}));

  std::vector<std::pair<std::int64_t, float>> expected;
  auto at = [&](std::int64_t ms, Fixture::Sender& s, float v, bool arrives) {
    ex.run_until(Time{std::chrono::milliseconds(ms)});
    s.fire(0, {v});
    if (arrives) expected.emplace_back(ms, v);
  };
  at(0, low, 1, true);     // nothing suppresses yet
  at(10, high, 2, true);   // opens [10, 110)
  at(10, low, 3, false);   // same instant: suppressed
  at(50, other, 4, true);  // equal priority is not suppressed
  at(109, low, 5, false);  // still inside the window
  at(110, low, 6, true);   // window closed at 110 exactly
  at(150, high, 7, true);  // reopens [150, 250)
  at(200, high, 8, true);  // extends to [200, 300)
  at(299, low, 9, false);
  at(300, low, 10, true);
  ex.run_until_idle();

  std::vector<std::pair<std::int64_t, float>> got;
  for (auto& r : col->received()) got.emplace_back(r.time.count() / 1000000, r.values[0]);
  EXPECT_EQ(got, expected);
  auto t = node.info(rx)->traffic;
  EXPECT_EQ(t.suppressed, 3u);
  EXPECT_EQ(t.attempted, 10u);
  EXPECT_EQ(t.delivered + t.dropped(), t.attempted);
}

TEST_F(Hooks, ExplicitSuppressionFromOutside) {
  auto [rx, col] = collector("rx");
  auto s = sender("s");
  ex.run_until_idle();
  ASSERT_TRUE(node.hook(s.id, rx, {.priority = 2}));
  ex.run_until(Time{5ms});
  ASSERT_TRUE(node.suppress(rx, 3, 20ms));  // [5, 25) for priority < 3
  ex.run_until(Time{24ms});
  s.fire(0, {1});
  ex.run_until(Time{25ms});
  s.fire(0, {2});
  ex.run_until_idle();
  ASSERT_EQ(col->count(), 1u);
  EXPECT_EQ(col->received()[0].values[0], 2.0f);
  EXPECT_FALSE(node.suppress(rx, 3, -1ms));
}

// Inhibition: a sender's output is blocked for exactly [t, t + window), to one receiver or all.
TEST_F(Hooks, InhibitionWindowIsExactInVirtualTime) {
  auto [a, ca] = collector("a");
  auto [b, cb] = collector("b");
  auto s = sender("s");
  ex.run_until_idle();
  ASSERT_TRUE(node.hook(s.id, a));
  ASSERT_TRUE(node.hook(s.id, b));
  ex.run_until(Time{10ms});
  ASSERT_TRUE(node.inhibit(s.id, a, 30ms));  // s -> a blocked for [10, 40)
  s.fire(0, {1});                            // b only
  ex.run_until(Time{39ms});
  s.fire(0, {2});  // b only
  ex.run_until(Time{40ms});
  s.fire(0, {3});                                  // both
  ASSERT_TRUE(node.inhibit(s.id, TaskId{}, 5ms));  // every output blocked for [40, 45)
  s.fire(0, {4});                                  // none
  ex.run_until(Time{45ms});
  s.fire(0, {5});  // both
  ex.run_until_idle();
  auto values = [](Collector* c) {
    std::vector<float> v;
    for (auto& r : c->received()) v.push_back(r.values[0]);
    return v;
  };
  EXPECT_EQ(values(ca), (std::vector<float>{3, 5}));
  EXPECT_EQ(values(cb), (std::vector<float>{1, 2, 3, 5}));
  EXPECT_EQ(node.info(a)->traffic.inhibited, 3u);
  EXPECT_EQ(node.info(b)->traffic.inhibited, 1u);
  auto [c, cc] = collector("c");
  EXPECT_FALSE(node.inhibit(s.id, c, 1ms));  // no hook from s to c
}

// A higher layer inhibits a lower layer's output from its own handler: the subsumption wiring
// of the paper's section III-A, with task code only.
TEST_F(Hooks, TaskInhibitsAnotherTaskFromItsHandler) {
  auto [motor, cm] = collector("motor");
  auto wander = *node.create("wander", std::make_unique<Emitter>(), {.period = 10ms});
  auto stop = std::make_unique<Scripted>();
  TaskId wander_id = wander;
  stop->tick = [wander_id](Scripted& self) {
    if (self.now() == Time{30ms}) {
      ASSERT_TRUE(self.node().inhibit(wander_id, TaskId{}, 35ms));  // [30, 65)
    }
  };
  ASSERT_TRUE(node.create("stopper", std::move(stop), {.priority = 10, .period = 10ms}));
  ASSERT_TRUE(node.hook(wander, motor));
  ex.run_until(Time{100ms});
  std::vector<std::int64_t> times;
  for (auto& r : cm->received()) times.push_back(r.time.count() / 1000000);
  // The stopper has the higher priority, so at 30 ms it inhibits before wander sends.
  EXPECT_EQ(times, (std::vector<std::int64_t>{10, 20, 70, 80, 90, 100}));
}

TEST_F(Hooks, DeletingAReceiverUnhooksItAndCountsWhatWasQueued) {
  auto [rx, col] = collector("rx", {.queue_capacity = 8});
  auto s = sender("s");
  ex.run_until_idle();
  ASSERT_TRUE(node.hook(s.id, rx));
  ASSERT_TRUE(node.suspend(rx));
  for (float v = 0; v < 5; ++v) s.fire(0, {v});
  EXPECT_EQ(node.queued(), 5u);
  ASSERT_TRUE(node.remove(rx));
  EXPECT_TRUE(node.hooks().empty());
  s.fire(0, {9});
  auto t = node.traffic();
  EXPECT_EQ(t.attempted, 5u);
  EXPECT_EQ(t.discarded, 5u);
  EXPECT_EQ(t.delivered + t.dropped(), t.attempted);
  EXPECT_FALSE(node.info(rx));
}

TEST_F(Hooks, SuspendedReceiverKeepsItsQueueAndCatchesUpOnResume) {
  auto [rx, col] = collector("rx", {.queue_capacity = 8});
  auto s = sender("s");
  ex.run_until_idle();
  ASSERT_TRUE(node.hook(s.id, rx, {.policy = QueuePolicy::kRefuse}));
  ASSERT_TRUE(node.suspend(rx));
  for (float v = 0; v < 3; ++v) s.fire(0, {v});
  ex.run_until_idle();
  EXPECT_EQ(col->count(), 0u);
  ASSERT_TRUE(node.resume(rx));
  ex.run_until_idle();
  EXPECT_EQ(col->count(), 3u);
}

TEST_F(Hooks, ListingShowsEveryHook) {
  auto [a, ca] = collector("a");
  auto s = sender("s");
  auto h = *node.hook(s.id, a, {.priority = 4, .policy = QueuePolicy::kRefuse});
  auto list = node.hooks();
  ASSERT_EQ(list.size(), 1u);
  EXPECT_EQ(list[0].id, h);
  EXPECT_EQ(list[0].sender_name, "s");
  EXPECT_EQ(list[0].receiver_name, "a");
  EXPECT_EQ(list[0].options.priority, 4);
  EXPECT_EQ(list[0].options.policy, QueuePolicy::kRefuse);
  EXPECT_FALSE(node.hook(s.id, TaskId{}));
  EXPECT_FALSE(node.unhook(HookId{99, 99}));
}

TEST_F(Hooks, PostFromOutsideUsesTheGivenPolicy) {
  auto [a, ca] = collector("a", {.queue_capacity = 1, .autostart = false});
  ASSERT_TRUE(node.post(a, Message{}));
  EXPECT_FALSE(node.post(a, Message{}));  // refused: queue full, not started
  ASSERT_TRUE(node.start(a));
  ex.run_until_idle();
  EXPECT_EQ(ca->count(), 1u);
  EXPECT_EQ(node.info(a)->traffic.refused, 1u);
}

}  // namespace
}  // namespace symb::os
