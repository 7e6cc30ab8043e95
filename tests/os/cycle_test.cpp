// Hook cycles (kMaxHops, message.hpp): tasks hooked in a ring that answer every message would keep
// a virtual-time run at one instant for ever and spin a thread executor's cores. The node cuts
// such a chain after kMaxHops answers: the run advances, the sender is faulted, and the error
// names the tasks of the cycle. Chains that end by themselves, however long under the bound, are
// left alone.
#include <atomic>
#include <chrono>
#include <thread>

#include <gtest/gtest.h>

#include "symb/kernel/thread_executor.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"

#include "test_tasks.hpp"

namespace symb::os {
namespace {

using namespace std::chrono_literals;
using kernel::Time;
using testing::Scripted;

// Answers every message it gets (the livelock of issue 15 item 1), counting them.
std::unique_ptr<Scripted> echo(std::atomic<std::uint64_t>& handled) {
  auto t = std::make_unique<Scripted>();
  t->message = [&handled](Scripted& self, const Message& m) {
    handled.fetch_add(1, std::memory_order_relaxed);
    self.send(0, {m.numbers().empty() ? 0.0f : m.numbers()[0] + 1});
  };
  return t;
}

std::size_t errors_in(SysLog& log) {
  std::size_t n = 0;
  for (const auto& e : log.since(0))
    if (e.level == LogLevel::kError) ++n;
  return n;
}

// Two echoes hooked both ways: a -> b -> a.
std::pair<TaskId, TaskId> echo_ring(Node& node, std::atomic<std::uint64_t>& handled) {
  const TaskId a = *node.create("a", echo(handled));
  const TaskId b = *node.create("b", echo(handled));
  EXPECT_TRUE(node.hook(a, b));
  EXPECT_TRUE(node.hook(b, a));
  return {a, b};
}

TEST(HookCycle, VirtualTimeRunAdvancesAndTheErrorNamesTheCycle) {
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"robot", 1});
  std::atomic<std::uint64_t> handled{0};
  const auto [a, b] = echo_ring(node, handled);
  // A bystander with a period: its ticks show that time goes on.
  int ticks = 0;
  auto t = std::make_unique<Scripted>();
  t->tick = [&ticks](Scripted&) { ++ticks; };
  ASSERT_TRUE(node.create("clock", std::move(t), {.period = 10ms}));
  ex.run_until(Time{5ms});
  ASSERT_TRUE(node.post(a, Message{}));

  const std::uint64_t events = ex.run_until(Time{1s});
  EXPECT_EQ(ex.now(), Time{1s});
  EXPECT_EQ(ticks, 100);
  EXPECT_LT(events, 2 * kMaxHops + 200u);
  EXPECT_EQ(handled.load(), kMaxHops + 1u);  // answers 0 .. kMaxHops were handled
  const std::string error = node.cycle_error();
  EXPECT_NE(error.find("node 'robot': message cycle"), std::string::npos) << error;
  // The task that would have sent the answer kMaxHops + 1 is faulted; the cycle reads from it.
  const bool a_cut = node.info(a)->state == TaskState::kFaulted;
  EXPECT_NE(a_cut, node.info(b)->state == TaskState::kFaulted);
  EXPECT_NE(error.find(a_cut ? "a -> b -> a" : "b -> a -> b"), std::string::npos) << error;
  EXPECT_EQ(errors_in(node.log()), 1u);
  EXPECT_EQ(node.longest_chain(), kMaxHops);
}

TEST(HookCycle, ALongerCycleIsNamedTaskByTask) {
  static_assert(kMaxHops % 3 == 1);
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"robot", 1});
  std::atomic<std::uint64_t> handled{0};
  const TaskId ids[] = {*node.create("sensor", echo(handled)), *node.create("controller", echo(handled)),
                        *node.create("wheels", echo(handled))};
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(node.hook(ids[i], ids[(i + 1) % 3]));
  ASSERT_TRUE(node.post(ids[0], Message{}));
  ex.run_until(Time{1s});
  // After kMaxHops answers, the next would be sent by the task kMaxHops % 3 = 1 step after
  // `sensor`.
  const std::string error = node.cycle_error();
  EXPECT_NE(error.find("controller -> wheels -> sensor -> controller"), std::string::npos) << error;
  EXPECT_EQ(node.info(ids[1])->state, TaskState::kFaulted);
}

TEST(HookCycle, AFanOutInsideTheCycleIsCutToo) {
  // a -> b, a -> c, b -> a, c -> a: every answer of `a` comes back twice.
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"robot", 1});
  std::atomic<std::uint64_t> handled{0};
  const TaskId a = *node.create("a", echo(handled));
  const TaskId b = *node.create("b", echo(handled));
  const TaskId c = *node.create("c", echo(handled));
  ASSERT_TRUE(node.hook(a, b));
  ASSERT_TRUE(node.hook(a, c));
  ASSERT_TRUE(node.hook(b, a));
  ASSERT_TRUE(node.hook(c, a));
  ASSERT_TRUE(node.post(a, Message{}));
  ex.run_until(Time{1s});
  EXPECT_EQ(ex.now(), Time{1s});
  EXPECT_FALSE(node.cycle_error().empty());
}

TEST(HookCycle, ChainsThatEndByThemselvesAreLeftAlone) {
  // A ping-pong of 5000 answers, and a pipeline of 200 tasks: long, under the bound, finite.
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"robot", 1});
  auto bounded = [] {
    auto t = std::make_unique<Scripted>();
    t->message = [](Scripted& self, const Message& m) {
      if (m.numbers()[0] < 5000) self.send(0, {m.numbers()[0] + 1});
    };
    return t;
  };
  const TaskId p = *node.create("ping", bounded());
  const TaskId q = *node.create("pong", bounded());
  ASSERT_TRUE(node.hook(p, q));
  ASSERT_TRUE(node.hook(q, p));
  std::atomic<std::uint64_t> handled{0};
  std::vector<TaskId> pipe;
  for (int i = 0; i < 200; ++i) {
    pipe.push_back(*node.create("stage" + std::to_string(i), echo(handled)));
    if (i > 0) {
      ASSERT_TRUE(node.hook(pipe[i - 1], pipe[i]));
    }
  }
  Message first;
  first.payload = Payload{1.0f};
  ASSERT_TRUE(node.post(p, first));
  ASSERT_TRUE(node.post(pipe[0], Message{}));
  ex.run_until(Time{1s});
  EXPECT_EQ(node.cycle_error(), "");
  EXPECT_EQ(errors_in(node.log()), 0u);
  EXPECT_EQ(handled.load(), 200u);
  EXPECT_EQ(node.longest_chain(), 4999u);
  for (const auto& i : node.tasks()) EXPECT_EQ(i.state, TaskState::kRunning) << i.name;
}

TEST(HookCycle, TicksAndOutsideInputStartAChainAfresh) {
  // A cycle that answers only on ticks is not a livelock: a tick's send starts at hop 0.
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"robot", 1});
  auto relay = std::make_unique<Scripted>();
  bool got = false;
  relay->message = [&got](Scripted&, const Message&) { got = true; };
  relay->tick = [&got](Scripted& self) {
    if (got) self.send(0, {1});
    got = false;
  };
  std::atomic<std::uint64_t> handled{0};
  const TaskId r = *node.create("relay", std::move(relay), {.period = 1ms});
  const TaskId e = *node.create("echo", echo(handled));
  ASSERT_TRUE(node.hook(r, e));
  ASSERT_TRUE(node.hook(e, r));
  ASSERT_TRUE(node.post(r, Message{}));
  ex.run_until(Time{15s});
  EXPECT_EQ(node.cycle_error(), "");
  EXPECT_GT(handled.load(), kMaxHops);  // more answers in all than kMaxHops, never in a row
  EXPECT_EQ(node.longest_chain(), 1u);
}

TEST(HookCycle, ThreadExecutorCutsTheCycleAndThenStaysQuiet) {
  kernel::ThreadExecutor ex;
  Node node(ex, {"robot", 1});
  std::atomic<std::uint64_t> handled{0};
  const auto [a, b] = echo_ring(node, handled);
  ASSERT_TRUE(node.post(a, Message{}));
  // Waits for what is asserted: the cut, then both tasks idle (a faulted, b with nothing to answer).
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  auto quiet = [&node, a = a, b = b] {
    const auto ia = node.info(a);
    const auto ib = node.info(b);
    return !node.cycle_error().empty() && (ia->state == TaskState::kFaulted || ib->state == TaskState::kFaulted) &&
           (ia->state == TaskState::kFaulted || ia->queue_depth == 0) &&
           (ib->state == TaskState::kFaulted || ib->queue_depth == 0);
  };
  while (!quiet() && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(1ms);
  ASSERT_TRUE(quiet()) << node.cycle_error();
  EXPECT_NE(node.cycle_error().find("message cycle"), std::string::npos);
  // Nothing more happens: the traffic no longer grows and the log holds the one error.
  const std::uint64_t after_cut = handled.load();
  EXPECT_LE(after_cut, kMaxHops + 2u);
  std::this_thread::sleep_for(50ms);
  EXPECT_EQ(handled.load(), after_cut);
  EXPECT_EQ(errors_in(node.log()), 1u);
}

}  // namespace
}  // namespace symb::os
