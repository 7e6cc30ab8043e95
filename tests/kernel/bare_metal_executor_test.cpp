#include "symb/kernel/bare_metal_executor.hpp"

#include <deque>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "kernel/recording_activity.hpp"

namespace symb::kernel {
namespace {

using namespace std::chrono_literals;

using BareRecorder = test_support::RecordingActivity;

struct BareMetalExecutorTest : ::testing::Test {
  std::vector<std::string> log;
  std::deque<BareRecorder> recorders;
  BareMetalExecutor ex{1ms, 4, [](const char* why) { throw std::runtime_error(why); }};
  BareRecorder& make(const std::string& name) { return recorders.emplace_back(name, ex, log); }
  // `n` SysTick interrupts, the main loop running what is ready after each.
  void ticks(int n) {
    for (int i = 0; i < n; ++i) {
      ex.on_tick_interrupt();
      ex.run_ready();
    }
  }
};

TEST_F(BareMetalExecutorTest, TicksAtExactPeriodsFromTheTickInterrupt) {
  BareRecorder& a = make("a");
  ex.attach(a, {0, 3ms, "a"});
  ex.run_ready();
  ticks(10);
  EXPECT_EQ(log, (std::vector<std::string>{"a:start@0", "a:tick@3", "a:tick@6", "a:tick@9"}));
  EXPECT_EQ(ex.next_due(), Time{12ms});
}

TEST_F(BareMetalExecutorTest, HighestPriorityReadyRunsFirstAndEqualsInAttachOrder) {
  BareRecorder& lo = make("lo");
  BareRecorder& hi = make("hi");
  BareRecorder& hi2 = make("hi2");
  ex.attach(lo, {1, 2ms, "lo"});
  ex.attach(hi, {5, 2ms, "hi"});
  ex.attach(hi2, {5, 2ms, "hi2"});
  ex.run_ready();
  ticks(2);
  EXPECT_EQ(log, (std::vector<std::string>{"hi:start@0", "hi2:start@0", "lo:start@0", "hi:tick@2", "hi2:tick@2",
                                           "lo:tick@2"}));
}

TEST_F(BareMetalExecutorTest, InputRunsToCompletionBeforeLowerWorkAndWakesCoalesce) {
  BareRecorder& sensor = make("sensor");
  BareRecorder& controller = make("controller");
  ex.attach(sensor, {3, 0ms, "sensor"});
  ex.attach(controller, {2, 5ms, "controller"});
  ex.run_ready();
  log.clear();
  // A chain: the sensor's input wakes the controller twice; the controller runs once, after the
  // sensor's handler returned, and before its own due tick (input comes before a tick).
  sensor.on_input = [&] {
    controller.slot->wake();
    controller.slot->wake();
  };
  ticks(4);
  sensor.slot->wake();
  ticks(1);
  EXPECT_EQ(log, (std::vector<std::string>{"sensor:input@5", "controller:input@5", "controller:tick@5"}));
}

TEST_F(BareMetalExecutorTest, SuspendKeepsInputAndTicksResumeOnePeriodLater) {
  BareRecorder& c = make("c");
  ex.attach(c, {0, 2ms, "c"});
  ex.run_ready();
  c.slot->suspend();
  c.slot->wake();
  ticks(5);
  EXPECT_EQ(log, (std::vector<std::string>{"c:start@0"}));
  c.slot->resume();
  ex.run_ready();
  ticks(2);
  EXPECT_EQ(log, (std::vector<std::string>{"c:start@0", "c:input@5", "c:tick@7"}));
}

TEST_F(BareMetalExecutorTest, ALateTickIsNotMadeUpButCounted) {
  BareRecorder& c = make("c");
  ex.attach(c, {0, 2ms, "c"});
  ex.run_ready();
  for (int i = 0; i < 7; ++i) ex.on_tick_interrupt();  // the main loop was busy for 7 ms
  ex.run_ready();
  ticks(2);
  EXPECT_EQ(log, (std::vector<std::string>{"c:start@0", "c:tick@7", "c:tick@9"}));
  EXPECT_EQ(ex.stats().ticks_late, 2u);  // the ticks due at 4 and 6 ms
}

TEST_F(BareMetalExecutorTest, DetachFromItsOwnHandlerStopsAfterItAndFreesTheSlot) {
  BareRecorder& a = make("a");
  BareRecorder& b = make("b");
  ex.attach(a, {0, 1ms, "a"});
  a.on_tick = [&] { a.slot->detach(); };
  ex.run_ready();
  ticks(3);
  EXPECT_EQ(log, (std::vector<std::string>{"a:start@0", "a:tick@1", "a:stop@1", "a:released@1"}));
  EXPECT_EQ(ex.stats().activities, 0u);
  ex.attach(b, {0, 0ms, "b"});
  ex.run_ready();
  EXPECT_EQ(log.back(), "b:start@3");
}

TEST_F(BareMetalExecutorTest, CapacityAndInjectAreBoundedAndRefusedByFail) {
  std::deque<BareRecorder> more;
  for (int i = 0; i < 4; ++i) ex.attach(more.emplace_back("m", ex, log), {0, 0ms, "m"});
  BareRecorder& extra = make("extra");
  EXPECT_THROW(ex.attach(extra, {0, 0ms, "extra"}), std::runtime_error);
  int ran = 0;
  for (int i = 0; i < 4; ++i) ex.inject([&] { ++ran; });
  EXPECT_THROW(ex.inject([] {}), std::runtime_error);
  ex.run_ready();
  EXPECT_EQ(ran, 4);
  EXPECT_EQ(ex.stats().injected, 4u);
  for (auto& m : more) m.slot->detach();
}

}  // namespace
}  // namespace symb::kernel
