// The two ends of a hook outside the node: a HookSink that is handed a sender's messages on the
// sender's own context, and Node::send_as, by which a source outside the node sends as a task
// standing for it. Both keep the hook's rules and its accounting (hook.hpp) exactly; together they
// carry a message from one node's task to another's with no thread between them.
#include <atomic>
#include <mutex>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "symb/kernel/thread_executor.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"

#include "support/eventually.hpp"
#include "test_tasks.hpp"

namespace symb::os {
namespace {

using namespace std::chrono_literals;
using kernel::Time;
using testing::Collector;
using testing::Scripted;

// Records what it is handed, and on which thread.
class RecordingSink final : public HookSink {
 public:
  explicit RecordingSink(std::string name) : HookSink(std::move(name)) {}
  std::function<void(const Message&)> on_each;
  std::vector<float> firsts() const {
    std::lock_guard lock(mu_);
    return firsts_;
  }
  std::vector<std::thread::id> threads() const {
    std::lock_guard lock(mu_);
    return threads_;
  }
  void on_message(const Message& m) override {
    {
      std::lock_guard lock(mu_);
      firsts_.push_back(m.payload.count > 0 ? m.payload.values[0] : -1.0f);
      threads_.push_back(std::this_thread::get_id());
    }
    if (on_each) on_each(m);
  }

 private:
  mutable std::mutex mu_;
  std::vector<float> firsts_;
  std::vector<std::thread::id> threads_;
};

const HookInfo* find_hook(const std::vector<HookInfo>& hooks, HookId id) {
  for (const HookInfo& h : hooks)
    if (h.id == id) return &h;
  return nullptr;
}

TEST(HookSink, IsHandedWhatTheHookLetsThroughAndCountsIt) {
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"n", 1});
  auto script = std::make_unique<Scripted>();
  Scripted* tx_task = script.get();
  const TaskId tx = *node.create("tx", std::move(script));
  const TaskId local = *node.create("local", std::make_unique<Collector>(), {.queue_capacity = 64});
  auto on_port1 = std::make_shared<RecordingSink>("wire.port1");
  auto any = std::make_shared<RecordingSink>("wire.any");
  const HookId h1 = *node.hook(tx, on_port1, {.priority = 2, .port = 1});
  const HookId h2 = *node.hook(tx, any);
  ASSERT_TRUE(node.hook(tx, local));
  ex.run_until_idle();

  float n = 0;
  auto send = [&](Port port) {
    tx_task->send(port, {n});
    n += 1;
  };
  send(0);  // any only
  send(1);  // both
  ASSERT_TRUE(node.set_hook_enabled(h2, false));
  send(1);  // port1 only; `any` skips it
  ASSERT_TRUE(node.set_hook_enabled(h2, true));
  ASSERT_TRUE(node.inhibit(tx, TaskId{}, 5ms));  // every hook of tx, the sinks' too
  send(1);
  ex.run_until(Time{5ms});
  send(1);
  EXPECT_EQ(on_port1->firsts(), (std::vector<float>{1, 2, 4}));
  EXPECT_EQ(any->firsts(), (std::vector<float>{0, 1, 4}));

  const auto hooks = node.hooks();
  const HookInfo* a = find_hook(hooks, h1);
  const HookInfo* b = find_hook(hooks, h2);
  ASSERT_NE(a, nullptr);
  ASSERT_NE(b, nullptr);
  EXPECT_FALSE(a->receiver.valid());
  EXPECT_EQ(a->receiver_name, "wire.port1");
  EXPECT_EQ(a->sink, on_port1);
  EXPECT_EQ(a->sender_name, "tx");
  EXPECT_EQ(a->accounting.sent, 5u);
  EXPECT_EQ(a->accounting.skipped, 1u);
  EXPECT_EQ(a->accounting.traffic.attempted, 4u);
  EXPECT_EQ(a->accounting.traffic.delivered, 3u);
  EXPECT_EQ(a->accounting.traffic.inhibited, 1u);
  EXPECT_EQ(a->accounting.queued, 0u);
  EXPECT_TRUE(a->accounting.closes());
  EXPECT_EQ(b->accounting.skipped, 1u);  // disabled once
  EXPECT_EQ(b->accounting.traffic.delivered, 3u);
  EXPECT_TRUE(b->accounting.closes());

  // Gone: no more calls, and its counts stay in the node's books.
  ASSERT_TRUE(node.unhook(h1));
  send(1);
  EXPECT_EQ(on_port1->firsts().size(), 3u);
  EXPECT_EQ(any->firsts().size(), 4u);
  ex.run_until_idle();
  const HookTraffic all = node.hook_traffic();
  EXPECT_TRUE(all.closes());
  EXPECT_EQ(all.traffic.delivered, 3u + 4u + 5u);  // port1, any, and `local` (all but the inhibited one)
  EXPECT_EQ(all.traffic.inhibited, 3u);
}

// More sinks than a send keeps at hand: each is handed the message once, in hook order.
TEST(HookSink, ManySinksOfOneSenderEachGetEveryMessage) {
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"n", 1});
  auto script = std::make_unique<Scripted>();
  Scripted* tx_task = script.get();
  const TaskId tx = *node.create("tx", std::move(script));
  std::vector<std::shared_ptr<RecordingSink>> sinks;
  std::vector<int> order;
  for (int k = 0; k < 7; ++k) {
    sinks.push_back(std::make_shared<RecordingSink>("wire" + std::to_string(k)));
    sinks.back()->on_each = [&order, k](const Message&) { order.push_back(k); };
    ASSERT_TRUE(node.hook(tx, sinks.back(), {.priority = k}));
  }
  ex.run_until_idle();
  tx_task->send(0, {1.0f});
  tx_task->send(0, {2.0f});
  for (const auto& sink : sinks) EXPECT_EQ(sink->firsts(), (std::vector<float>{1, 2}));
  EXPECT_EQ(order, (std::vector<int>{6, 5, 4, 3, 2, 1, 0, 6, 5, 4, 3, 2, 1, 0}));  // highest priority first
  EXPECT_TRUE(node.hook_traffic().closes());
  ASSERT_TRUE(node.remove(tx));  // its sink hooks go with it, their counts kept
  const HookTraffic all = node.hook_traffic();
  EXPECT_EQ(all.traffic.delivered, 14u);
  EXPECT_TRUE(all.closes());
}

TEST(HookSink, RefusesAWindowADuplicateAndNoSink) {
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"n", 1});
  const TaskId tx = *node.create("tx", std::make_unique<Scripted>());
  auto sink = std::make_shared<RecordingSink>("wire");
  EXPECT_NE(node.hook(tx, sink, {.suppress_window = 1ms}).error().find("no queue for a suppression window"),
            std::string::npos);
  ASSERT_TRUE(node.hook(tx, sink, {.port = 2}));
  EXPECT_NE(node.hook(tx, sink, {.port = 2}).error().find("already hooked to sink 'wire' on port 2"),
            std::string::npos);
  EXPECT_TRUE(node.hook(tx, sink, {.port = 3}));  // another port is another hook
  EXPECT_FALSE(node.hook(tx, std::shared_ptr<HookSink>{}));
  EXPECT_FALSE(node.hook(TaskId{}, sink));
}

TEST(SendAs, DeliversThroughTheStandInsHooksUnderTheReceiversRules) {
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"n", 1});
  const TaskId inlet = *node.create("inlet", std::make_unique<Scripted>());
  auto col = std::make_unique<Collector>();
  Collector* got = col.get();
  const TaskId rx = *node.create("rx", std::move(col), {.queue_capacity = 2});
  auto boss_task = std::make_unique<Scripted>();
  Scripted* boss = boss_task.get();
  const TaskId b = *node.create("boss", std::move(boss_task));
  const TaskId other = *node.create("other", std::make_unique<Collector>());
  const HookId in = *node.hook(inlet, rx, {.priority = 1, .policy = QueuePolicy::kRefuse});
  ASSERT_TRUE(node.hook(b, rx, {.priority = 5, .suppress_window = 10ms}));
  ASSERT_TRUE(node.hook(inlet, other, {.port = 7}));
  ex.run_until_idle();

  // A full queue refuses under the hook's policy.
  for (float v : {1.0f, 2.0f, 3.0f}) ASSERT_TRUE(node.send_as(inlet, 0, Payload({v})));
  ex.run_until_idle();
  ASSERT_EQ(got->count(), 2u);
  EXPECT_EQ(got->received()[0].source, inlet);
  EXPECT_EQ(got->received()[1].values, (std::vector<float>{2.0f}));
  // A higher-priority delivery opens a window that drops what the stand-in sends into it.
  ex.run_until(Time{20ms});
  boss->send(0, {9.0f});
  ASSERT_TRUE(node.send_as(inlet, 0, Payload({4.0f})));
  ex.run_until(Time{30ms});
  ASSERT_TRUE(node.send_as(inlet, 0, Payload({5.0f})));
  ex.run_until_idle();
  std::vector<float> firsts;
  for (const auto& r : got->received()) firsts.push_back(r.values[0]);
  EXPECT_EQ(firsts, (std::vector<float>{1, 2, 9, 5}));
  EXPECT_EQ(got->received().back().time, Time{30ms});

  const auto hooks = node.hooks();
  const HookInfo* h = find_hook(hooks, in);
  ASSERT_NE(h, nullptr);
  EXPECT_EQ(h->accounting.sent, 5u);  // every send_as, as the stand-in's own sends
  EXPECT_EQ(h->accounting.traffic.attempted, 5u);
  EXPECT_EQ(h->accounting.traffic.delivered, 3u);
  EXPECT_EQ(h->accounting.traffic.refused, 1u);
  EXPECT_EQ(h->accounting.traffic.suppressed, 1u);
  EXPECT_TRUE(h->accounting.closes());
  EXPECT_EQ(node.info(other)->traffic.attempted, 0u);  // port 7 only: skipped
  EXPECT_TRUE(node.hook_traffic().closes());

  ASSERT_TRUE(node.remove(inlet));
  EXPECT_NE(node.send_as(inlet, 0, Payload({6.0f})).error().find("has no task"), std::string::npos);
}

// Two nodes joined both ways by a sink that sends as a stand-in on the other node: each message
// crosses on its sender's thread alone, while other threads read both nodes' books. No lock of
// one node is held while the other's are taken (the sink runs outside its sender's locks), so
// this neither deadlocks nor races (it runs under ThreadSanitizer).
class SendAsSink final : public HookSink {
 public:
  SendAsSink(Node& to, TaskId as) : HookSink("to." + to.name()), to_(to), as_(as) {}
  void on_message(const Message& m) override { (void)to_.send_as(as_, m.port, m.payload); }

 private:
  Node& to_;
  TaskId as_;
};

class Forward final : public Task {
 protected:
  void on_message(const Message& m) override { send(m.port, m.payload); }
};

TEST(HookSink, CarriesMessagesBetweenNodesOnTheSendersThreadBothWays) {
  kernel::ThreadExecutor ex;
  Node a(ex, {"a", 1}), b(ex, {"b", 2});
  constexpr int kEach = 500;
  struct Side {
    TaskId tx, inlet, rx;
    Collector* got = nullptr;
  };
  auto make = [](Node& n) {
    Side s;
    s.tx = *n.create("tx", std::make_unique<Forward>(), {.queue_capacity = kEach});
    s.inlet = *n.create("inlet", std::make_unique<Scripted>());
    auto c = std::make_unique<Collector>();
    s.got = c.get();
    s.rx = *n.create("rx", std::move(c), {.queue_capacity = kEach});
    return s;
  };
  Side sa = make(a), sb = make(b);
  ASSERT_TRUE(a.hook(sa.inlet, sa.rx, {.policy = QueuePolicy::kRefuse}));
  ASSERT_TRUE(b.hook(sb.inlet, sb.rx, {.policy = QueuePolicy::kRefuse}));
  ASSERT_TRUE(a.hook(sa.tx, std::make_shared<SendAsSink>(b, sb.inlet)));
  ASSERT_TRUE(b.hook(sb.tx, std::make_shared<SendAsSink>(a, sa.inlet)));
  std::atomic<bool> done{false};
  std::thread reader([&] {
    while (!done.load()) {
      (void)a.hook_traffic();
      (void)b.hooks();
    }
  });
  for (int i = 0; i < kEach; ++i) {
    Message m;
    m.payload = Payload({float(i)});
    ASSERT_TRUE(a.post(sa.tx, m));
    ASSERT_TRUE(b.post(sb.tx, m));
  }
  const auto until = std::chrono::steady_clock::now() + 10s;
  while ((sa.got->count() < kEach || sb.got->count() < kEach) && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(1ms);
  done.store(true);
  reader.join();
  ASSERT_EQ(sb.got->count(), std::size_t(kEach));
  ASSERT_EQ(sa.got->count(), std::size_t(kEach));
  for (int i = 0; i < kEach; ++i) ASSERT_EQ(sb.got->received()[i].values[0], float(i));  // in order
  for (Node* n : {&a, &b}) {
    for (const HookInfo& h : n->hooks()) {
      EXPECT_TRUE(h.accounting.closes()) << h.sender_name << " -> " << h.receiver_name;
      EXPECT_EQ(h.accounting.traffic.delivered, std::uint64_t(kEach)) << h.sender_name << " -> " << h.receiver_name;
    }
  }
}

TEST(HookSink, IsCalledOnTheSendersOwnThread) {
  kernel::ThreadExecutor ex;
  Node node(ex, {"n", 1});
  std::atomic<std::thread::id> handler_thread{};
  auto script = std::make_unique<Scripted>();
  script->message = [&](Scripted& self, const Message& m) {
    handler_thread.store(std::this_thread::get_id());
    self.send(m.port, m.payload);
  };
  const TaskId tx = *node.create("tx", std::move(script));
  auto sink = std::make_shared<RecordingSink>("wire");
  ASSERT_TRUE(node.hook(tx, sink));
  ASSERT_TRUE(node.post(tx, Message{}));
  symb::testing::eventually([&] { return !sink->threads().empty(); });
  ASSERT_EQ(sink->threads().size(), 1u);
  EXPECT_EQ(sink->threads()[0], handler_thread.load());
  EXPECT_NE(sink->threads()[0], std::this_thread::get_id());
}

}  // namespace
}  // namespace symb::os
