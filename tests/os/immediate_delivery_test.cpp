// Tasks that take their messages at once (Task::take_messages_at_once): handled inside the
// sender's send under a non-concurrent executor, queued as usual everywhere else, with the same
// accounting, a bounded nesting and a handler that may rewire the node mid-send. And tasks that
// take their notifications at once (Task::take_notifications_at_once): on_notify inside the
// notifying handler only when the woken activation would have been the next event anyway, also
// when a lockstep lane is notified just before its window.
#include <algorithm>
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "symb/kernel/lockstep_executor.hpp"
#include "symb/kernel/thread_executor.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"

#include "support/eventually.hpp"
#include "test_tasks.hpp"

namespace symb::os {
namespace {

using namespace std::chrono_literals;
using testing::Collector;
using testing::Scripted;

class AtOnceCollector : public Collector {
 public:
  AtOnceCollector() { take_messages_at_once(); }
};

class AtOnceScripted : public Scripted {
 public:
  AtOnceScripted() { take_messages_at_once(); }
};

TEST(ImmediateDelivery, TheReceiverHandlesTheMessageBeforeTheSendReturns) {
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"bot", 1});
  auto at_once = std::make_unique<AtOnceCollector>();
  auto queued = std::make_unique<Collector>();
  AtOnceCollector* a = at_once.get();
  Collector* q = queued.get();
  std::vector<std::size_t> seen_at_once, seen_queued;  // each receiver's count right after a send
  auto sender = std::make_unique<Scripted>();
  sender->tick = [&](Scripted& s) {
    s.send(0, {static_cast<float>(s.now().count())});
    seen_at_once.push_back(a->count());
    seen_queued.push_back(q->count());
  };
  const TaskId sid = *node.create("sender", std::move(sender), {.period = 10ms, .autostart = false});
  const TaskId aid = *node.create("at_once", std::move(at_once));
  const TaskId qid = *node.create("queued", std::move(queued));
  ASSERT_TRUE(node.hook(sid, aid));
  ASSERT_TRUE(node.hook(sid, qid));
  ASSERT_TRUE(node.start(sid));
  ex.run_for(30ms);
  EXPECT_EQ(seen_at_once, (std::vector<std::size_t>{1, 2, 3}));
  EXPECT_EQ(seen_queued, (std::vector<std::size_t>{0, 1, 2}));
  // The message is the one a queue would have handed over: same time, source and numbers.
  const std::vector<testing::Received> got = a->received(), queued_got = q->received();
  ASSERT_EQ(got.size(), 3u);
  ASSERT_EQ(queued_got.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(got[i].time, kernel::Duration{(i + 1) * 10ms});
    EXPECT_EQ(got[i].source, sid);
    EXPECT_EQ(got[i].values, queued_got[i].values);
  }
  EXPECT_EQ(node.info(aid)->traffic.delivered, 3u);
  EXPECT_EQ(node.info(aid)->traffic.attempted, 3u);
  EXPECT_TRUE(node.hook_traffic().closes());
  for (const HookInfo& h : node.hooks()) EXPECT_TRUE(h.accounting.closes()) << h.receiver_name;
}

TEST(ImmediateDelivery, UnderTheThreadExecutorTheMessageIsQueuedForTheReceiversThread) {
  kernel::ThreadExecutor ex;
  Node node(ex, {"bot", 1});
  auto at_once = std::make_unique<AtOnceCollector>();
  AtOnceCollector* a = at_once.get();
  std::atomic<std::thread::id> sender_thread{}, receiver_thread{};
  a->on_each = [&](const Message&) { receiver_thread = std::this_thread::get_id(); };
  auto sender = std::make_unique<Scripted>();
  sender->tick = [&](Scripted& s) {
    sender_thread = std::this_thread::get_id();
    s.send(0, {1.0f});
  };
  const TaskId sid = *node.create("sender", std::move(sender), {.period = 5ms, .autostart = false});
  const TaskId aid = *node.create("at_once", std::move(at_once));
  ASSERT_TRUE(node.hook(sid, aid));
  ASSERT_TRUE(node.start(sid));
  ASSERT_TRUE(symb::testing::eventually([&] { return a->count() >= 2; }));
  node.clear();
  EXPECT_NE(sender_thread.load(), receiver_thread.load());
}

TEST(ImmediateDelivery, ASendFromOutsideAnyHandlerIsQueued) {
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"bot", 1});
  auto at_once = std::make_unique<AtOnceCollector>();
  AtOnceCollector* a = at_once.get();
  const TaskId sid = *node.create("sender", std::make_unique<Scripted>());
  const TaskId aid = *node.create("at_once", std::move(at_once));
  ASSERT_TRUE(node.hook(sid, aid));
  ex.run_for(0ms);
  ASSERT_TRUE(node.send_as(sid, 0, Payload{2.0f}));
  EXPECT_EQ(a->count(), 0u);
  EXPECT_EQ(node.info(aid)->queue_depth, 1u);
  ex.run_for(0ms);
  EXPECT_EQ(a->count(), 1u);
  EXPECT_TRUE(node.hook_traffic().closes());
}

TEST(ImmediateDelivery, NestingStopsAtItsBoundAndTheRestIsQueuedNotLost) {
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"bot", 1});
  constexpr int kChain = 2 * Node::kMaxImmediateDepth + 3;
  int active = 0, deepest = 0;
  std::vector<TaskId> ids;
  std::vector<int> handled(kChain, 0);
  // The source's tick sends one message down the chain.
  auto src = std::make_unique<Scripted>();
  src->tick = [](Scripted& s) { s.send(0, {1.0f}); };
  const TaskId source = *node.create("source", std::move(src), {.period = 10ms, .autostart = false});
  for (int i = 0; i < kChain; ++i) {
    auto t = std::make_unique<AtOnceScripted>();
    t->message = [&, i](Scripted& s, const Message& m) {
      ++active;
      deepest = std::max(deepest, active);
      ++handled[static_cast<std::size_t>(i)];
      s.send(0, m.payload);
      --active;
    };
    ids.push_back(*node.create("link" + std::to_string(i), std::move(t)));
    ASSERT_TRUE(node.hook(i == 0 ? source : ids[static_cast<std::size_t>(i) - 1], ids.back()));
  }
  ASSERT_TRUE(node.start(source));
  ex.run_for(50ms);
  // Link kMaxImmediateDepth is queued: its activation and the links it reaches at once nest one
  // deeper than the source's tick and the first links.
  EXPECT_EQ(deepest, Node::kMaxImmediateDepth + 1);
  EXPECT_EQ(handled, std::vector<int>(kChain, 5));
  EXPECT_TRUE(node.hook_traffic().closes());
}

TEST(ImmediateDelivery, TwoTasksAnsweringEachOtherAreNeverReentered) {
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"bot", 1});
  constexpr float kLast = 100;
  bool inside[2] = {false, false};
  bool reentered = false;
  std::vector<float> heard;
  TaskId ids[2];
  for (int i = 0; i < 2; ++i) {
    auto t = std::make_unique<AtOnceScripted>();
    t->message = [&, i](Scripted& s, const Message& m) {
      if (inside[i]) reentered = true;
      inside[i] = true;
      const float v = m.numbers()[0];
      heard.push_back(v);
      if (v < kLast) s.send(0, {v + 1});
      inside[i] = false;
    };
    ids[i] = *node.create(i == 0 ? "ping" : "pong", std::move(t));
  }
  ASSERT_TRUE(node.hook(ids[0], ids[1]));
  ASSERT_TRUE(node.hook(ids[1], ids[0]));
  auto starter = std::make_unique<Scripted>();
  starter->tick = [](Scripted& self) {
    if (self.now() == kernel::Duration{10ms}) self.send(0, {0.0f});
  };
  const TaskId start = *node.create("start", std::move(starter), {.period = 10ms, .autostart = false});
  ASSERT_TRUE(node.hook(start, ids[0]));
  ASSERT_TRUE(node.start(start));
  ex.run_for(10ms);
  EXPECT_FALSE(reentered);
  ASSERT_EQ(heard.size(), static_cast<std::size_t>(kLast) + 1);
  for (std::size_t k = 0; k < heard.size(); ++k) EXPECT_EQ(heard[k], static_cast<float>(k));
  EXPECT_TRUE(node.hook_traffic().closes());
}

TEST(ImmediateDelivery, AReceiverMayUnhookOtherReceiversInTheMiddleOfTheSend) {
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"bot", 1});
  auto later = std::make_unique<Collector>();
  Collector* l = later.get();
  auto rest = std::make_unique<Collector>();
  Collector* r = rest.get();
  auto sender = std::make_unique<Scripted>();
  sender->tick = [](Scripted& self) { self.send(0, {1.0f}); };
  const TaskId sid = *node.create("sender", std::move(sender), {.period = 10ms, .autostart = false});
  HookId later_hook{};
  auto first = std::make_unique<AtOnceScripted>();
  int first_heard = 0;
  first->message = [&](Scripted& self, const Message&) {
    ++first_heard;
    if (first_heard == 2) {
      EXPECT_TRUE(self.node().unhook(later_hook));
    }
  };
  const TaskId fid = *node.create("first", std::move(first));
  const TaskId lid = *node.create("later", std::move(later));
  const TaskId rid = *node.create("rest", std::move(rest));
  // The sender's hooks in priority order: first, later, rest.
  ASSERT_TRUE(node.hook(sid, fid, {.priority = 3}));
  later_hook = *node.hook(sid, lid, {.priority = 2});
  ASSERT_TRUE(node.hook(sid, rid, {.priority = 1}));
  ASSERT_TRUE(node.start(sid));
  ex.run_for(40ms);
  EXPECT_EQ(first_heard, 4);
  // Unhooked during the second send, after that send had reached every hook: the receivers that
  // take messages at once are handed it last.
  EXPECT_EQ(l->count(), 2u);
  EXPECT_EQ(r->count(), 4u);
  EXPECT_TRUE(node.hook_traffic().closes());
}

TEST(ImmediateDelivery, WhatAReceiverSendsFromItsHandlerReachesTheOthersBehindTheMessage) {
  // sender -> a, sender -> b, a -> b; a and b take messages at once. Through queues b hears the
  // sender's message first, then a's answer; so it does here.
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"bot", 1});
  std::vector<float> b_heard;
  auto a = std::make_unique<AtOnceScripted>();
  a->message = [](Scripted& self, const Message& m) { self.send(0, {m.numbers()[0] + 100}); };
  auto b = std::make_unique<AtOnceScripted>();
  b->message = [&](Scripted&, const Message& m) { b_heard.push_back(m.numbers()[0]); };
  auto sender = std::make_unique<Scripted>();
  sender->tick = [](Scripted& self) { self.send(0, {1.0f}); };
  const TaskId sid = *node.create("sender", std::move(sender), {.period = 10ms, .autostart = false});
  const TaskId aid = *node.create("a", std::move(a));
  const TaskId bid = *node.create("b", std::move(b));
  ASSERT_TRUE(node.hook(sid, aid, {.priority = 2}));
  ASSERT_TRUE(node.hook(sid, bid, {.priority = 1}));
  ASSERT_TRUE(node.hook(aid, bid));
  ASSERT_TRUE(node.start(sid));
  ex.run_for(10ms);
  EXPECT_EQ(b_heard, (std::vector<float>{1, 101}));
  EXPECT_TRUE(node.hook_traffic().closes());
}

TEST(ImmediateDelivery, AReceiverDeletedByAnEarlierOneInTheSameSendLosesNothingUncounted) {
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"bot", 1});
  TaskId victim{};
  auto killer = std::make_unique<AtOnceScripted>();
  killer->message = [&](Scripted& self, const Message&) { EXPECT_TRUE(self.node().remove(victim)); };
  auto v = std::make_unique<AtOnceCollector>();
  auto sender = std::make_unique<Scripted>();
  sender->tick = [](Scripted& self) { self.send(0, {1.0f}); };
  const TaskId sid = *node.create("sender", std::move(sender), {.period = 10ms, .autostart = false});
  const TaskId kid = *node.create("killer", std::move(killer));
  victim = *node.create("victim", std::move(v));
  ASSERT_TRUE(node.hook(sid, kid, {.priority = 2}));
  ASSERT_TRUE(node.hook(sid, victim, {.priority = 1}));
  ASSERT_TRUE(node.start(sid));
  ex.run_for(10ms);
  EXPECT_FALSE(node.info(victim));
  const TrafficCounters t = node.traffic();
  EXPECT_EQ(t.attempted, 2u);
  EXPECT_EQ(t.delivered + t.dropped(), 2u);
  EXPECT_EQ(t.discarded, 1u);  // the victim's message, queued when it could no longer take it
  EXPECT_TRUE(node.hook_traffic().closes());
}

class CountingSink final : public HookSink {
 public:
  CountingSink() : HookSink("counter") {}
  std::size_t count = 0;
  void on_message(const Message&) override { ++count; }
};

TEST(ImmediateDelivery, ASenderHookedToASinkAndToAReceiverThatTakesAtOnceReachesBoth) {
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"bot", 1});
  auto at_once = std::make_unique<AtOnceCollector>();
  AtOnceCollector* a = at_once.get();
  auto sink = std::make_shared<CountingSink>();
  std::vector<std::size_t> seen;
  auto sender = std::make_unique<Scripted>();
  sender->tick = [&](Scripted& self) {
    self.send(0, {1.0f});
    seen.push_back(a->count());
  };
  const TaskId sid = *node.create("sender", std::move(sender), {.period = 10ms, .autostart = false});
  ASSERT_TRUE(node.hook(sid, *node.create("at_once", std::move(at_once))));
  ASSERT_TRUE(node.hook(sid, sink));
  ASSERT_TRUE(node.start(sid));
  ex.run_for(30ms);
  EXPECT_EQ(seen, (std::vector<std::size_t>{1, 2, 3}));
  EXPECT_EQ(sink->count, 3u);
  EXPECT_TRUE(node.hook_traffic().closes());
}

// Counts its notifications and, from the second, what `order` says ran before it.
class Notified : public Task {
 public:
  explicit Notified(bool at_once, std::vector<std::string>* order = nullptr) : order_(order) {
    if (at_once) take_notifications_at_once();
  }
  int count() const { return count_; }
  using Task::notify;

 protected:
  void on_notify() override {
    ++count_;
    if (order_ != nullptr) order_->push_back("notified");
  }

 private:
  std::vector<std::string>* order_;
  int count_ = 0;
};

TEST(ImmediateNotification, OnNotifyRunsBeforeTheNotifyFromAHandlerReturns) {
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"bot", 1});
  auto at_once = std::make_unique<Notified>(true);
  auto woken = std::make_unique<Notified>(false);
  Notified* a = at_once.get();
  Notified* w = woken.get();
  std::vector<int> seen_at_once, seen_woken;  // each one's count right after the notify
  auto driver = std::make_unique<Scripted>();
  driver->tick = [&](Scripted&) {
    a->notify();
    w->notify();
    seen_at_once.push_back(a->count());
    seen_woken.push_back(w->count());
  };
  ASSERT_TRUE(node.create("at_once", std::move(at_once)));
  ASSERT_TRUE(node.create("woken", std::move(woken)));
  ASSERT_TRUE(node.create("driver", std::move(driver), {.priority = 5, .period = 10ms}));
  const std::uint64_t events = ex.run_for(35ms);
  EXPECT_EQ(seen_at_once, (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(seen_woken, (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(a->count(), 3);
  EXPECT_EQ(w->count(), 3);
  // Three starts, three ticks, three activations of the woken task: none of the other one.
  EXPECT_EQ(events, 9u);
}

TEST(ImmediateNotification, AnEventThatComesFirstAtTheInstantStillComesFirst) {
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"bot", 1});
  std::vector<std::string> order;
  auto notified = std::make_unique<Notified>(true, &order);
  Notified* n = notified.get();
  auto driver = std::make_unique<Scripted>();
  driver->tick = [&](Scripted&) { n->notify(); };
  auto other = std::make_unique<Scripted>();
  other->tick = [&](Scripted&) { order.push_back("other"); };
  ASSERT_TRUE(node.create("notified", std::move(notified), {.priority = 1}));
  ASSERT_TRUE(node.create("driver", std::move(driver), {.priority = 5, .period = 10ms}));
  // Ticks at the driver's instants, above the notified task: a wake would have run after it.
  ASSERT_TRUE(node.create("other", std::move(other), {.priority = 3, .period = 10ms}));
  ex.run_for(25ms);
  EXPECT_EQ(order, (std::vector<std::string>{"other", "notified", "other", "notified"}));
}

TEST(ImmediateNotification, ANotifyFromOutsideAnyHandlerWakesTheTask) {
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"bot", 1});
  auto notified = std::make_unique<Notified>(true);
  Notified* n = notified.get();
  const TaskId id = *node.create("notified", std::move(notified));
  ex.run_for(1ms);
  n->notify();
  EXPECT_EQ(n->count(), 0);
  ASSERT_TRUE(node.notify(id));  // under the node's lock: never at once
  EXPECT_EQ(n->count(), 0);
  ex.run_for(1ms);
  EXPECT_EQ(n->count(), 1);  // one activation for both
}

// The world runner's shape: a task on the main lane of a lockstep executor notifies a task on each
// robot's lane through for_each_lane_before_its_window(). The call is made in the lane's window
// as from a handler of the lane, so a task that takes its notifications at once does there
// instead of costing the lane an activation, and which threads run the lanes changes nothing.
TEST(ImmediateNotification, ALockstepLaneTakesANotificationMadeBeforeItsWindowAtOnce) {
  constexpr std::size_t kLanes = 4;
  struct Run {
    std::vector<std::vector<int>> seen_at_once, seen_woken;  // per lane, each count after the notify
    std::vector<int> at_once_count, woken_count;
    std::uint64_t events = 0;
  };
  auto run = [&](unsigned threads) {
    kernel::LockstepExecutor ex({.threads = threads});
    Run r;
    r.seen_at_once.resize(kLanes);
    r.seen_woken.resize(kLanes);
    std::vector<std::unique_ptr<Node>> robots;
    std::vector<Notified*> at_once, woken;
    for (std::size_t i = 0; i < kLanes; ++i) {
      robots.push_back(std::make_unique<Node>(ex.lane(i), NodeConfig{"bot", i + 1}));
      auto a = std::make_unique<Notified>(true);
      auto w = std::make_unique<Notified>(false);
      at_once.push_back(a.get());
      woken.push_back(w.get());
      EXPECT_TRUE(robots.back()->create("at_once", std::move(a)));
      EXPECT_TRUE(robots.back()->create("woken", std::move(w)));
    }
    Node world(ex, {"world", 100});
    auto driver = std::make_unique<Scripted>();
    driver->tick = [&](Scripted&) {
      ex.for_each_lane_before_its_window(kLanes, [&](std::size_t i) {
        at_once[i]->notify();
        woken[i]->notify();
        r.seen_at_once[i].push_back(at_once[i]->count());
        r.seen_woken[i].push_back(woken[i]->count());
      });
    };
    EXPECT_TRUE(world.create("driver", std::move(driver), {.priority = 5, .period = 10ms}));
    // The driver ticks at 10, 20 and 30 ms; each tick's calls open its lanes' window.
    r.events = ex.run_until(kernel::Time{35ms});
    for (std::size_t i = 0; i < kLanes; ++i) {
      r.at_once_count.push_back(at_once[i]->count());
      r.woken_count.push_back(woken[i]->count());
    }
    return r;
  };
  const Run one = run(1);
  for (std::size_t i = 0; i < kLanes; ++i) {
    EXPECT_EQ(one.seen_at_once[i], (std::vector<int>{1, 2, 3})) << "lane " << i;
    EXPECT_EQ(one.seen_woken[i], (std::vector<int>{0, 1, 2})) << "lane " << i;
  }
  EXPECT_EQ(one.at_once_count, std::vector<int>(kLanes, 3));
  EXPECT_EQ(one.woken_count, std::vector<int>(kLanes, 3));
  for (const unsigned threads : {2u, 4u}) {
    const Run many = run(threads);
    EXPECT_EQ(many.seen_at_once, one.seen_at_once) << threads << " threads";
    EXPECT_EQ(many.seen_woken, one.seen_woken) << threads << " threads";
    EXPECT_EQ(many.events, one.events) << threads << " threads";
  }
}

}  // namespace
}  // namespace symb::os
