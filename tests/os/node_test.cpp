#include "symb/os/node.hpp"

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "symb/kernel/thread_executor.hpp"
#include "symb/kernel/virtual_time_executor.hpp"

#include "support/eventually.hpp"
#include "test_tasks.hpp"

namespace symb::os {
namespace {

using namespace std::chrono_literals;
using testing::Collector;
using testing::Emitter;
using testing::Scripted;

TEST(Node, LifecycleStatesAndListing) {
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"robot", 1});
  auto id = node.create("emit", std::make_unique<Emitter>(), {.priority = 3, .period = 10ms, .autostart = false});
  ASSERT_TRUE(id);
  EXPECT_EQ(node.info(*id)->state, TaskState::kCreated);
  ASSERT_TRUE(node.start(*id));
  EXPECT_FALSE(node.start(*id));
  EXPECT_EQ(node.info(*id)->state, TaskState::kRunning);
  ASSERT_TRUE(node.suspend(*id));
  EXPECT_EQ(node.info(*id)->state, TaskState::kSuspended);
  EXPECT_FALSE(node.suspend(*id));
  ASSERT_TRUE(node.resume(*id));
  ASSERT_TRUE(node.set_priority(*id, 7));
  auto list = node.tasks();
  ASSERT_EQ(list.size(), 1u);
  EXPECT_EQ(list[0].name, "emit");
  EXPECT_EQ(list[0].priority, 7);
  EXPECT_EQ(list[0].period, kernel::Duration{10ms});
  EXPECT_EQ(list[0].type, "-");
  ASSERT_TRUE(node.remove(*id));
  EXPECT_FALSE(node.info(*id));
  EXPECT_FALSE(node.remove(*id));
  EXPECT_EQ(node.task_count(), 0u);
}

TEST(Node, NamesAreUniqueAndValidated) {
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {});
  ASSERT_TRUE(node.create("a", std::make_unique<Collector>()));
  auto dup = node.create("a", std::make_unique<Collector>());
  ASSERT_FALSE(dup);
  EXPECT_NE(dup.error().find("already has a task named 'a'"), std::string::npos);
  EXPECT_FALSE(node.create("", std::make_unique<Collector>()));
  EXPECT_FALSE(node.create("bad name", std::make_unique<Collector>()));
  EXPECT_FALSE(node.create("b", nullptr));
  EXPECT_FALSE(node.create("c", std::make_unique<Collector>(), {.queue_capacity = 0}));
  EXPECT_TRUE(node.find("a"));
  EXPECT_FALSE(node.find("zzz"));
}

TEST(Node, StaleHandlesNeverReachANewTaskInTheSameSlot) {
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {});
  auto old_id = *node.create("a", std::make_unique<Collector>());
  ASSERT_TRUE(node.remove(old_id));
  auto new_id = *node.create("b", std::make_unique<Collector>());
  EXPECT_EQ(new_id.index, old_id.index);
  EXPECT_NE(new_id.generation, old_id.generation);
  EXPECT_FALSE(node.suspend(old_id));
  EXPECT_FALSE(node.info(old_id));
  EXPECT_TRUE(node.info(new_id));
  EXPECT_FALSE(node.suspend(TaskId{}));
}

TEST(Node, TickingFollowsPeriodAndSuspension) {
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {});
  auto emitter = std::make_unique<Emitter>();
  Emitter* e = emitter.get();
  auto id = *node.create("emit", std::move(emitter), {.period = 10ms});
  ex.run_until(kernel::Time{100ms});
  EXPECT_EQ(e->emitted(), 10);
  ASSERT_TRUE(node.suspend(id));
  ex.run_until(kernel::Time{200ms});
  EXPECT_EQ(e->emitted(), 10);
  ASSERT_TRUE(node.resume(id));
  ex.run_until(kernel::Time{250ms});
  EXPECT_EQ(e->emitted(), 15);
  ASSERT_TRUE(node.set_period(id, 25ms));
  ex.run_until(kernel::Time{300ms});
  EXPECT_EQ(e->emitted(), 17);
}

TEST(Node, AnExceptionFaultsOnlyThatTaskAndIsLogged) {
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {});
  auto bad = std::make_unique<Scripted>();
  bad->tick = [](Scripted&) { throw std::runtime_error("sensor on fire"); };
  auto bad_id = *node.create("bad", std::move(bad), {.period = 10ms});
  auto good = std::make_unique<Emitter>();
  Emitter* g = good.get();
  auto good_id = *node.create("good", std::move(good), {.period = 10ms});
  ex.run_until(kernel::Time{50ms});
  EXPECT_EQ(node.info(bad_id)->state, TaskState::kFaulted);
  EXPECT_EQ(node.info(good_id)->state, TaskState::kRunning);
  EXPECT_EQ(g->emitted(), 5);
  bool logged = false;
  for (const auto& e : node.log().since(0))
    logged |= e.level == LogLevel::kError && e.source == "bad" && e.text.find("sensor on fire") != std::string::npos;
  EXPECT_TRUE(logged);
  EXPECT_FALSE(node.resume(bad_id));  // a faulted task is deleted, not resumed
  EXPECT_TRUE(node.remove(bad_id));
}

TEST(Node, FaultInStartOrMessageHandlers) {
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {});
  auto s = std::make_unique<Scripted>();
  s->start = [](Scripted&) { throw 42; };
  auto sid = *node.create("s", std::move(s));
  auto m = std::make_unique<Scripted>();
  m->message = [](Scripted&, const Message&) { throw std::logic_error("bad message"); };
  auto mid = *node.create("m", std::move(m));
  ex.run_until_idle();
  ASSERT_TRUE(node.post(mid, Message{}));
  ex.run_until_idle();
  EXPECT_EQ(node.info(sid)->state, TaskState::kFaulted);
  EXPECT_EQ(node.info(mid)->state, TaskState::kFaulted);
  EXPECT_EQ(node.info(mid)->traffic.delivered, 1u);
}

TEST(Node, TasksCanRewireTheNodeFromTheirHandlers) {
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {});
  TaskId child;
  bool stopped = false;
  auto parent = std::make_unique<Scripted>();
  parent->tick = [&](Scripted& self) {
    if (self.now() == kernel::Time{10ms}) {
      auto c = std::make_unique<Scripted>();
      c->stop = [&](Scripted&) { stopped = true; };
      child = *self.node().create("child", std::move(c), {.period = 5ms});
    } else if (self.now() == kernel::Time{20ms}) {
      ASSERT_TRUE(self.node().remove(child));
      ASSERT_TRUE(self.node().remove(self.id()));  // deleting itself from its own handler
    }
  };
  auto pid = *node.create("parent", std::move(parent), {.period = 10ms});
  ex.run_until(kernel::Time{15ms});
  EXPECT_TRUE(node.find("child"));
  ex.run_until(kernel::Time{30ms});
  EXPECT_TRUE(stopped);
  EXPECT_FALSE(node.find("child"));
  EXPECT_FALSE(node.info(pid));
  EXPECT_EQ(node.task_count(), 0u);
}

TEST(Node, RandomStreamsDependOnSeedAndName) {
  kernel::VirtualTimeExecutor ex;
  Node a(ex, {"a", 7}), b(ex, {"b", 7}), c(ex, {"c", 8});
  EXPECT_EQ(a.random_stream("x").next_u64(), b.random_stream("x").next_u64());
  EXPECT_NE(a.random_stream("x").next_u64(), a.random_stream("y").next_u64());
  EXPECT_NE(a.random_stream("x").next_u64(), c.random_stream("x").next_u64());
  // A task's stream depends on the node seed and its own name only, not on creation order.
  std::uint64_t first_a = 0, first_b = 0;
  auto ta = std::make_unique<Scripted>();
  ta->start = [&](Scripted& s) { first_a = s.random().next_u64(); };
  auto tb = std::make_unique<Scripted>();
  tb->start = [&](Scripted& s) { first_b = s.random().next_u64(); };
  ASSERT_TRUE(a.create("other", std::make_unique<Collector>()));
  ASSERT_TRUE(a.create("t", std::move(ta)));
  ASSERT_TRUE(b.create("t", std::move(tb)));
  ex.run_until_idle();
  EXPECT_EQ(first_a, first_b);
}

TEST(Node, DestructorStopsEveryTaskOnBothExecutors) {
  int stops = 0;
  {
    kernel::VirtualTimeExecutor ex;
    Node node(ex, {});
    for (int i = 0; i < 3; ++i) {
      auto s = std::make_unique<Scripted>();
      s->stop = [&](Scripted&) { ++stops; };
      ASSERT_TRUE(node.create("s" + std::to_string(i), std::move(s), {.period = 1ms}));
    }
    ex.run_for(10ms);
  }
  EXPECT_EQ(stops, 3);
  std::atomic<int> thread_starts{0};
  std::atomic<int> thread_stops{0};
  {
    kernel::ThreadExecutor ex;
    Node node(ex, {});
    for (int i = 0; i < 3; ++i) {
      auto s = std::make_unique<Scripted>();
      s->start = [&](Scripted&) { thread_starts.fetch_add(1); };
      s->stop = [&](Scripted&) { thread_stops.fetch_add(1); };
      ASSERT_TRUE(node.create("s" + std::to_string(i), std::move(s), {.period = 1ms}));
    }
    // on_stop runs only for a task whose on_start ran: wait for that, not for a fixed time (a
    // thread not yet scheduled when the node goes would never start, nor stop).
    const auto end = std::chrono::steady_clock::now() + 10s;
    while (thread_starts.load() < 3 && std::chrono::steady_clock::now() < end) std::this_thread::sleep_for(1ms);
    ASSERT_EQ(thread_starts.load(), 3);
  }
  EXPECT_EQ(thread_stops.load(), 3);
}

TEST(Node, ThreadExecutorRunsTheSameTaskCode) {
  kernel::ThreadExecutor ex;
  Node node(ex, {});
  auto c = std::make_unique<Collector>();
  Collector* col = c.get();
  auto rx = *node.create("rx", std::move(c));
  auto tx = *node.create("tx", std::make_unique<Emitter>(), {.period = 1ms});
  ASSERT_TRUE(node.hook(tx, rx));
  symb::testing::eventually([&] { return col->count() >= 20; });
  ASSERT_GE(col->count(), 20u);
  auto got = col->received();
  // A slow reader may lose the oldest to keep-newest, but order is kept.
  for (std::size_t i = 1; i < got.size(); ++i) EXPECT_LT(got[i - 1].values.at(0), got[i].values.at(0));
}

// Payload copies carry the numbers in use and share the blob (they skip the unused tail).
TEST(Payload, CopiesAndMovesKeepTheNumbersInUseAndShareTheBlob) {
  struct Big final : Blob {
    std::uint32_t kind() const override { return 7; }
  };
  Payload a{1.5f, -2.0f, 3.25f};
  a.blob = std::make_shared<Big>();
  const Payload b = a;  // copy
  EXPECT_EQ(std::vector<float>(b.numbers().begin(), b.numbers().end()), (std::vector<float>{1.5f, -2.0f, 3.25f}));
  EXPECT_EQ(b.blob, a.blob);
  Payload c;
  for (float& v : c.values) EXPECT_EQ(v, 0.0f);  // a default payload is all zeros
  c = Payload{9.0f};
  c = b;  // copy-assign over a shorter one
  EXPECT_EQ(c.count, 3);
  EXPECT_EQ(c.values[2], 3.25f);
  Payload d = std::move(c);
  EXPECT_EQ(d.count, 3);
  EXPECT_EQ(d.values[1], -2.0f);
  EXPECT_EQ(d.blob, a.blob);
  EXPECT_EQ(c.blob, nullptr);  // NOLINT(bugprone-use-after-move): the blob moved with it
  std::vector<float> many(40, 1.0f);
  const Payload e{std::span<const float>(many)};
  EXPECT_EQ(e.count, Payload::kInlineValues);
  Payload f;
  f = e;
  EXPECT_EQ(f.numbers().size(), Payload::kInlineValues);
}

// Records notifications and messages in the order the node hands them over, and what it sends
// from on_notify (which starts a chain of its own, as a tick does).
class NotifiedTask : public Task {
 public:
  std::vector<std::string> seen;

 protected:
  void on_notify() override {
    seen.push_back("notify");
    send(0, {1.0f});
  }
  void on_message(const Message& m) override { seen.push_back("message " + std::to_string(m.numbers()[0])); }
};

TEST(Node, NotifyWakesATaskOnceWithoutAMessage) {
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"robot", 1});
  auto task = std::make_unique<NotifiedTask>();
  NotifiedTask* t = task.get();
  const TaskId id = *node.create("dev", std::move(task));
  auto sink = std::make_unique<Collector>();
  Collector* c = sink.get();
  const TaskId sink_id = *node.create("sink", std::move(sink));
  ASSERT_TRUE(node.hook(id, sink_id));
  ex.run_until_idle();

  // Three notifications and a message before the task runs: one on_notify, first, then the message.
  ASSERT_TRUE(node.notify(id));
  Message m;
  m.payload = Payload{7.0f};
  ASSERT_TRUE(node.post(id, m));
  ASSERT_TRUE(node.notify(id));
  ASSERT_TRUE(node.notify(id));
  ex.run_until_idle();
  EXPECT_EQ(t->seen, (std::vector<std::string>{"notify", "message 7.000000"}));
  // Nothing was queued for a notification: only the posted message is in the task's traffic.
  EXPECT_EQ(node.info(id)->traffic.attempted, 1u);
  EXPECT_EQ(node.info(id)->traffic.delivered, 1u);
  ASSERT_EQ(c->count(), 1u);
  EXPECT_EQ(node.longest_chain(), 0u);  // the send from on_notify started a chain: 0 hops

  // Suspended, a notification waits for resume; it is not lost and not doubled.
  ASSERT_TRUE(node.suspend(id));
  ASSERT_TRUE(node.notify(id));
  ASSERT_TRUE(node.notify(id));
  ex.run_until_idle();
  EXPECT_EQ(t->seen.size(), 2u);
  ASSERT_TRUE(node.resume(id));
  ex.run_until_idle();
  EXPECT_EQ(t->seen.size(), 3u);
  EXPECT_EQ(t->seen.back(), "notify");

  // A task not started yet gets it when it starts.
  auto later = std::make_unique<NotifiedTask>();
  NotifiedTask* l = later.get();
  const TaskId later_id = *node.create("later", std::move(later), {.autostart = false});
  ASSERT_TRUE(node.notify(later_id));
  ex.run_until_idle();
  EXPECT_TRUE(l->seen.empty());
  ASSERT_TRUE(node.start(later_id));
  ex.run_until_idle();
  EXPECT_EQ(l->seen, std::vector<std::string>{"notify"});

  // An unknown or removed task is an error, not a crash.
  ASSERT_TRUE(node.remove(later_id));
  const auto gone = node.notify(later_id);
  ASSERT_FALSE(gone);
  EXPECT_NE(gone.error().find("has no task"), std::string::npos);
  EXPECT_FALSE(node.notify(TaskId{}));
}

TEST(Node, NotifyFromAnotherThreadUnderTheThreadExecutor) {
  kernel::ThreadExecutor ex;
  Node node(ex, {"robot", 1});
  auto sink = std::make_unique<Collector>();
  Collector* c = sink.get();
  auto task = std::make_unique<NotifiedTask>();
  const TaskId id = *node.create("dev", std::move(task));
  const TaskId sink_id = *node.create("sink", std::move(sink));
  ASSERT_TRUE(node.hook(id, sink_id, {.policy = QueuePolicy::kRefuse}));
  // Each notification is followed by waiting for its send: every one must run on_notify.
  for (int i = 0; i < 50; ++i) {
    ASSERT_TRUE(node.notify(id));
    for (int spin = 0; spin < 20000 && c->count() < static_cast<std::size_t>(i + 1); ++spin)
      std::this_thread::sleep_for(std::chrono::microseconds(50));
    ASSERT_EQ(c->count(), static_cast<std::size_t>(i + 1));
  }
}

// A device's notifier as a sensor task makes one: attached in on_start, calling the task's own
// notify() (no lookup), which a test then calls as the device would.
class SelfNotifiedTask : public NotifiedTask {
 public:
  std::function<void()> notifier;
  std::atomic<bool> ready{false};  // the notifier is made (on_start ran)

 protected:
  void on_start() override {
    notifier = [this] { notify(); };
    ready.store(true, std::memory_order_release);
  }
};

TEST(Task, NotifyFromItsOwnNotifierActsAsNodeNotify) {
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"robot", 1});
  auto task = std::make_unique<SelfNotifiedTask>();
  SelfNotifiedTask* t = task.get();
  const TaskId id = *node.create("dev", std::move(task));
  auto sink = std::make_unique<Collector>();
  Collector* c = sink.get();
  ASSERT_TRUE(node.hook(id, *node.create("sink", std::move(sink))));
  ex.run_until_idle();
  ASSERT_TRUE(t->ready.load());

  // Three notifications and a message before the task runs: one on_notify, first, then the message.
  t->notifier();
  Message m;
  m.payload = Payload{7.0f};
  ASSERT_TRUE(node.post(id, m));
  t->notifier();
  t->notifier();
  ex.run_until_idle();
  EXPECT_EQ(t->seen, (std::vector<std::string>{"notify", "message 7.000000"}));
  EXPECT_EQ(node.info(id)->traffic.attempted, 1u);  // nothing was queued for the notifications
  EXPECT_EQ(c->count(), 1u);

  // Suspended, a notification waits for resume; it is not lost and not doubled.
  ASSERT_TRUE(node.suspend(id));
  t->notifier();
  t->notifier();
  ex.run_until_idle();
  EXPECT_EQ(t->seen.size(), 2u);
  ASSERT_TRUE(node.resume(id));
  ex.run_until_idle();
  ASSERT_EQ(t->seen.size(), 3u);
  EXPECT_EQ(t->seen.back(), "notify");
  EXPECT_EQ(c->count(), 2u);
}

TEST(Task, NotifyFromAnotherThreadUnderTheThreadExecutor) {
  kernel::ThreadExecutor ex;
  Node node(ex, {"robot", 1});
  auto sink = std::make_unique<Collector>();
  Collector* c = sink.get();
  auto task = std::make_unique<SelfNotifiedTask>();
  SelfNotifiedTask* t = task.get();
  const TaskId id = *node.create("dev", std::move(task));
  ASSERT_TRUE(node.hook(id, *node.create("sink", std::move(sink)), {.policy = QueuePolicy::kRefuse}));
  for (int spin = 0; spin < 20000 && !t->ready.load(std::memory_order_acquire); ++spin)
    std::this_thread::sleep_for(std::chrono::microseconds(50));
  ASSERT_TRUE(t->ready.load(std::memory_order_acquire));
  // Each notification, made on this thread as a device's driver would, is followed by waiting
  // for its send: every one must run on_notify.
  for (int i = 0; i < 50; ++i) {
    t->notifier();
    for (int spin = 0; spin < 20000 && c->count() < static_cast<std::size_t>(i + 1); ++spin)
      std::this_thread::sleep_for(std::chrono::microseconds(50));
    ASSERT_EQ(c->count(), static_cast<std::size_t>(i + 1));
  }
}

}  // namespace
}  // namespace symb::os
