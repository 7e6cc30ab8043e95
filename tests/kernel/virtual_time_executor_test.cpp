#include "symb/kernel/virtual_time_executor.hpp"

#include <algorithm>
#include <atomic>
#include <deque>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "kernel/recording_activity.hpp"

namespace symb::kernel {
namespace {

using namespace std::chrono_literals;

using Recorder = test_support::RecordingActivity;

// The executor is declared last so it is destroyed first, while its activities still exist.
struct VirtualTimeExecutorTest : ::testing::Test {
  std::vector<std::string> log;
  std::deque<Recorder> recorders;
  VirtualTimeExecutor ex;
  Recorder& make(const std::string& name) { return recorders.emplace_back(name, ex, log); }
};

TEST_F(VirtualTimeExecutorTest, TicksAtExactPeriods) {
  Recorder& a = make("a");
  ex.attach(a, {0, 30ms, "a"});
  ex.run_until(Time{100ms});
  EXPECT_EQ(log, (std::vector<std::string>{"a:start@0", "a:tick@30", "a:tick@60", "a:tick@90"}));
  EXPECT_EQ(ex.now(), Time{100ms});
}

TEST_F(VirtualTimeExecutorTest, HigherPriorityFirstAtTheSameInstant) {
  Recorder& lo = make("lo");
  Recorder& hi = make("hi");
  ex.attach(lo, {1, 10ms, "lo"});
  ex.attach(hi, {5, 10ms, "hi"});
  ex.run_until(Time{10ms});
  EXPECT_EQ(log, (std::vector<std::string>{"hi:start@0", "lo:start@0", "hi:tick@10", "lo:tick@10"}));
}

// Inputs woken at the current instant wait apart from the timed events (a short list, not the
// heap); the order is still time, then priority, then the order they were scheduled in, across
// both: a tick queued a period earlier goes before an input of its priority woken now.
TEST_F(VirtualTimeExecutorTest, InputsWokenNowMeetQueuedTicksInPriorityThenScheduleOrder) {
  Recorder& a = make("a");
  Recorder& b = make("b");
  Recorder& c = make("c");
  Recorder& d = make("d");
  Recorder& e = make("e");
  Recorder& f = make("f");
  Recorder& g = make("g");
  ex.attach(a, {5, 10ms, "a"});
  ex.attach(b, {1, 10ms, "b"});
  ex.attach(c, {3, {}, "c"});
  ex.attach(d, {3, {}, "d"});
  ex.attach(e, {0, {}, "e"});
  ex.attach(f, {7, {}, "f"});
  ex.attach(g, {1, {}, "g"});
  ex.run_until_idle(Time{0});
  log.clear();
  a.on_tick = [&] {
    c.slot->wake();
    e.slot->wake();
    d.slot->wake();
    g.slot->wake();
    f.slot->wake();
    c.slot->wake();  // already due: once
  };
  ex.run_until(Time{10ms});
  EXPECT_EQ(log, (std::vector<std::string>{"a:tick@10", "f:input@10", "c:input@10", "d:input@10", "b:tick@10",
                                           "g:input@10", "e:input@10"}));
  EXPECT_EQ(ex.pending_events(), 2u);  // the next ticks of a and b
  EXPECT_EQ(ex.next_event_time(), Time{20ms});
}

TEST_F(VirtualTimeExecutorTest, ManyWakesOneInput) {
  Recorder& a = make("a");
  ex.attach(a, {});
  ex.run_until_idle();
  a.slot->wake();
  a.slot->wake();
  a.slot->wake();
  ex.run_until_idle();
  EXPECT_EQ(log, (std::vector<std::string>{"a:start@0", "a:input@0"}));
}

TEST_F(VirtualTimeExecutorTest, SuspendStopsTicksAndInputResumeRestartsThem) {
  Recorder& a = make("a");
  ex.attach(a, {0, 10ms, "a"});
  ex.run_until(Time{15ms});
  a.slot->suspend();
  a.slot->wake();
  ex.run_until(Time{45ms});
  a.slot->resume();
  ex.run_until(Time{56ms});
  EXPECT_EQ(log, (std::vector<std::string>{"a:start@0", "a:tick@10", "a:input@45", "a:tick@55"}));
}

TEST_F(VirtualTimeExecutorTest, DetachFromOwnHandlerStopsAfterIt) {
  Recorder& a = make("a");
  a.on_tick = [&] { a.slot->detach(); };
  ex.attach(a, {0, 10ms, "a"});
  ex.run_until(Time{50ms});
  EXPECT_EQ(log, (std::vector<std::string>{"a:start@0", "a:tick@10", "a:stop@10", "a:released@10"}));
  EXPECT_EQ(ex.pending_events(), 0u);
}

TEST_F(VirtualTimeExecutorTest, DetachOutsideRunIsImmediate) {
  Recorder& a = make("a");
  ex.attach(a, {0, 10ms, "a"});
  ex.run_until(Time{0ms});
  a.slot->detach();
  EXPECT_EQ(log, (std::vector<std::string>{"a:start@0", "a:stop@0", "a:released@0"}));
  ex.run_until(Time{100ms});
  EXPECT_EQ(log.size(), 3u);  // the queued tick of the detached activity is stale
}

TEST_F(VirtualTimeExecutorTest, NeverStartedActivityIsReleasedWithoutStop) {
  Recorder& a = make("a");
  ex.attach(a, {});
  a.slot->detach();
  EXPECT_EQ(log, (std::vector<std::string>{"a:released@0"}));
}

TEST_F(VirtualTimeExecutorTest, SetPeriodRestartsChain) {
  Recorder& a = make("a");
  ex.attach(a, {0, 10ms, "a"});
  ex.run_until(Time{12ms});
  a.slot->set_period(25ms);
  ex.run_until(Time{70ms});
  EXPECT_EQ(log, (std::vector<std::string>{"a:start@0", "a:tick@10", "a:tick@37", "a:tick@62"}));
}

// A handler that says its ticks before t are not needed skips them on the chain's own grid: the
// next tick is the first multiple of the period at or after t (t itself when it is on the grid).
// A new period or a resume starts a chain that knows nothing of the hint.
TEST_F(VirtualTimeExecutorTest, SkippedTicksKeepTheChainsGrid) {
  Recorder& a = make("a");
  ex.attach(a, {0, 10ms, "a"});
  int ticks = 0;
  a.on_tick = [&] {
    ++ticks;
    if (ticks == 1) a.slot->skip_ticks_before(Time{35ms});  // next: 40, not 20 or 30
    if (ticks == 2) a.slot->skip_ticks_before(Time{60ms});  // on the grid: 60 itself
    if (ticks == 4) a.slot->skip_ticks_before(Time{200ms});
  };
  ex.run_until(Time{75ms});
  EXPECT_EQ(log, (std::vector<std::string>{"a:start@0", "a:tick@10", "a:tick@40", "a:tick@60", "a:tick@70"}));
  log.clear();
  a.slot->set_period(10ms);  // from 75 ms: 85, 95, ... whatever the hint of the tick at 70
  ex.run_until(Time{100ms});
  EXPECT_EQ(log, (std::vector<std::string>{"a:tick@85", "a:tick@95"}));
  log.clear();
  a.on_tick = [&] { a.slot->skip_ticks_before(Time{1s}); };
  ex.run_until(Time{110ms});  // the tick at 105 skips to 1 s
  a.slot->suspend();
  a.slot->resume();  // a new chain from 110 ms
  a.on_tick = nullptr;
  ex.run_until(Time{135ms});
  EXPECT_EQ(log, (std::vector<std::string>{"a:tick@105", "a:tick@120", "a:tick@130"}));
}

// A hint from an input handler reaches a tick already due: new input at 15 ms makes the tick of
// 20 ms idle, so it is left out (the call says so) and the chain goes on at 30 on its grid. A hint
// that reaches no pending tick leaves nothing out; in a heap too large to look through the tick
// runs as due.
TEST_F(VirtualTimeExecutorTest, AHintFromInputLeavesOutATickAlreadyDue) {
  Recorder& a = make("a");
  Recorder& b = make("b");
  ex.attach(a, {0, 10ms, "a"});
  ex.attach(b, {1, 15ms, "b"});
  std::vector<std::uint64_t> left_out;
  b.on_tick = [&] {
    if (ex.now() == Time{15ms}) a.slot->wake();
  };
  a.on_input = [&] {
    left_out.push_back(a.slot->skip_ticks_before(Time{21ms}));
    left_out.push_back(a.slot->skip_ticks_before(Time{25ms}));  // the tick is at 30 now
  };
  ex.run_until(Time{45ms});
  EXPECT_EQ(left_out, (std::vector<std::uint64_t>{1, 0}));
  EXPECT_EQ(log, (std::vector<std::string>{"b:start@0", "a:start@0", "a:tick@10", "b:tick@15", "a:input@15",
                                           "b:tick@30", "a:tick@30", "a:tick@40", "b:tick@45"}));

  std::vector<std::string> crowded_log;
  std::deque<Recorder> others;  // outlives the executor, which stops them as it goes
  VirtualTimeExecutor crowded;
  for (int i = 0; i < 20; ++i) crowded.attach(others.emplace_back("o", crowded, crowded_log), {0, 7ms, "o"});
  Recorder& c = others.emplace_back("c", crowded, crowded_log);
  crowded.attach(c, {0, 10ms, "c"});
  std::uint64_t crowded_left_out = 9;
  c.on_input = [&] { crowded_left_out = c.slot->skip_ticks_before(Time{21ms}); };
  crowded.run_until(Time{15ms});
  c.slot->wake();  // its input runs at 15, before the tick of 20
  crowded_log.clear();
  crowded.run_until(Time{20ms});
  EXPECT_EQ(crowded_left_out, 0u);
  EXPECT_NE(std::find(crowded_log.begin(), crowded_log.end(), "c:tick@20"), crowded_log.end());
}

TEST_F(VirtualTimeExecutorTest, StopReturnsEarly) {
  Recorder& a = make("a");
  a.on_tick = [&] {
    if (ex.now() == Time{20ms}) ex.stop();
  };
  ex.attach(a, {0, 10ms, "a"});
  ex.run_until(Time{100ms});
  EXPECT_EQ(ex.now(), Time{20ms});
}

TEST_F(VirtualTimeExecutorTest, InjectedWorkRunsOnTheExecutorThreadBetweenEvents) {
  Recorder& a = make("a");
  ex.attach(a, {0, 10ms, "a"});
  int ran = 0;
  std::thread::id where;
  std::thread outside([&] {
    ex.inject([&] {
      ++ran;
      where = std::this_thread::get_id();
      a.slot->wake();
    });
  });
  outside.join();
  EXPECT_EQ(ran, 0);  // nothing runs until the executor's thread gets to it
  ex.run_until(Time{5ms});
  EXPECT_EQ(ran, 1);
  EXPECT_EQ(where, std::this_thread::get_id());
  EXPECT_EQ(log, (std::vector<std::string>{"a:start@0", "a:input@0"}));
}

TEST_F(VirtualTimeExecutorTest, WaitInjectedPacesAgainstOutsideThreads) {
  std::atomic<int> sum{0};
  std::thread outside([&] {
    for (int i = 1; i <= 100; ++i) ex.inject([&sum, i] { sum.fetch_add(i); });
  });
  std::size_t ran = 0;
  for (int tries = 0; tries < 1000 && ran < 100; ++tries) ran += ex.wait_injected(std::chrono::milliseconds(10));
  outside.join();
  ran += ex.run_injected();
  EXPECT_EQ(ran, 100u);
  EXPECT_EQ(sum.load(), 5050);
}

// on_own_context: true only inside a run, on the running thread, so a simulated device may skip
// the inject() hand-over there while a real reader thread never does.
TEST_F(VirtualTimeExecutorTest, OwnContextOnlyInsideARunOnItsThread) {
  Recorder& a = make("a");
  ex.attach(a, {0, 10ms, "a"});
  std::vector<bool> inside;
  bool other_thread = true;
  a.on_tick = [&] {
    inside.push_back(ex.on_own_context());
    std::thread t([&] { other_thread = ex.on_own_context(); });
    t.join();
  };
  EXPECT_FALSE(ex.on_own_context());
  ex.run_until(Time{20ms});
  EXPECT_EQ(inside, (std::vector<bool>{true, true}));
  EXPECT_FALSE(other_thread);
  EXPECT_FALSE(ex.on_own_context());
  ex.run_until_idle(Time{30ms});
  EXPECT_EQ(inside.size(), 3u);
  EXPECT_FALSE(ex.on_own_context());
}

// Forty activities on `e` with mixed priorities (i mod 5) and periods; each tick wakes another
// one's input at the same instant.
void wire_forty(VirtualTimeExecutor& e, std::deque<Recorder>& rs, std::vector<std::string>& log) {
  for (int i = 0; i < 40; ++i) rs.emplace_back("r" + std::to_string(i), e, log);
  for (std::size_t i = 0; i < 40; ++i) {
    Recorder& next = rs[(i + 7) % 40];
    rs[i].on_tick = [&next] { next.slot->wake(); };
    e.attach(rs[i], {static_cast<int>(i % 5), std::chrono::milliseconds(3 + i % 11), rs[i].name});
  }
}

// The event heap under load: events scheduled from handlers at the current instant among ticks
// of many periods must come out in (time, priority, scheduling) order, the same every run.
TEST_F(VirtualTimeExecutorTest, ManyEventsComeOutInTimePriorityOrder) {
  wire_forty(ex, recorders, log);
  ex.run_until(Time{500ms});
  // Back from "rN:what@ms"; priority is N mod 5. Every tick of an instant was queued a period
  // before it, so within the instant the ticks come out by priority, highest first; inputs woken
  // by those ticks join the instant in between.
  struct Seen {
    long long ms;
    int priority;
    bool tick;
  };
  std::vector<Seen> order;
  for (const std::string& line : log) {
    const auto colon = line.find(':'), at = line.find('@');
    const int index = std::stoi(line.substr(1, colon - 1));
    order.push_back({std::stoll(line.substr(at + 1)), index % 5, line.find(":tick@") != std::string::npos});
  }
  ASSERT_GT(order.size(), 2000u);
  std::size_t inputs = 0;
  const Seen* last_tick = nullptr;
  for (std::size_t i = 0; i < order.size(); ++i) {
    if (i > 0) {
      ASSERT_LE(order[i - 1].ms, order[i].ms) << log[i];
    }
    if (!order[i].tick) {
      ++inputs;
      continue;
    }
    if (last_tick != nullptr && last_tick->ms == order[i].ms) {
      ASSERT_GE(last_tick->priority, order[i].priority) << log[i];
    }
    last_tick = &order[i];
  }
  EXPECT_GT(inputs, 1000u);
  // Same inputs, same run: a second executor gives the same log.
  std::vector<std::string> first = log;
  log.clear();
  {
    VirtualTimeExecutor ex2;
    std::deque<Recorder> rs2;
    wire_forty(ex2, rs2, log);
    ex2.run_until(Time{500ms});
    std::vector<std::string> second = log;
    for (auto& r : rs2) r.slot->detach();
    EXPECT_EQ(first, second);
  }
}

}  // namespace
}  // namespace symb::kernel
