#include "symb/kernel/thread_executor.hpp"

#include <atomic>
#include <chrono>
#include <thread>

#include <gtest/gtest.h>

#include "support/eventually.hpp"

namespace symb::kernel {
namespace {

using namespace std::chrono_literals;
using symb::testing::eventually;

struct Counter final : Activity {
  void on_activity_attached(ActivitySlot& s) override { slot = &s; }
  void on_activity_start() override { started = true; }
  void on_activity_input() override { inputs.fetch_add(1); }
  void on_activity_tick() override { ticks.fetch_add(1); }
  void on_activity_stop() override { stopped = true; }
  void on_activity_released() override { released = true; }
  ActivitySlot* slot = nullptr;
  std::atomic<bool> started{false}, stopped{false}, released{false};
  std::atomic<int> inputs{0}, ticks{0};
};

TEST(ThreadExecutor, StartsTicksAndStops) {
  ThreadExecutor ex;
  Counter c;
  ex.attach(c, {0, 5ms, "c"});
  ASSERT_TRUE(eventually([&] { return c.ticks.load() >= 3; }));
  EXPECT_TRUE(c.started);
  c.slot->detach();
  ASSERT_TRUE(eventually([&] { return c.released.load(); }));
  EXPECT_TRUE(c.stopped);
  EXPECT_EQ(ex.thread_count(), 0u);
}

TEST(ThreadExecutor, WakeRunsInput) {
  ThreadExecutor ex;
  Counter c;
  ex.attach(c, {});
  c.slot->wake();
  ASSERT_TRUE(eventually([&] { return c.inputs.load() >= 1; }));
  c.slot->detach();
  ASSERT_TRUE(eventually([&] { return c.released.load(); }));
}

TEST(ThreadExecutor, SuspendedActivityGetsNoInputUntilResumed) {
  ThreadExecutor ex;
  Counter c;
  ex.attach(c, {});
  ASSERT_TRUE(eventually([&] { return c.started.load(); }));
  c.slot->suspend();
  c.slot->wake();
  std::this_thread::sleep_for(30ms);
  EXPECT_EQ(c.inputs.load(), 0);
  c.slot->resume();
  ASSERT_TRUE(eventually([&] { return c.inputs.load() == 1; }));
  c.slot->detach();
  ASSERT_TRUE(eventually([&] { return c.released.load(); }));
}

TEST(ThreadExecutor, DestructorStopsEverything) {
  Counter a, b;
  {
    ThreadExecutor ex;
    ex.attach(a, {0, 1ms, "a"});
    ex.attach(b, {});
  }
  EXPECT_TRUE(a.released);
  EXPECT_TRUE(b.released);
}

TEST(ThreadExecutor, PriorityMappingIsClampedToFifoRange) {
  EXPECT_EQ(ThreadExecutor::os_priority(1000), 99);
  EXPECT_EQ(ThreadExecutor::os_priority(-1000), 1);
  EXPECT_LT(ThreadExecutor::os_priority(-1), ThreadExecutor::os_priority(1));
}

TEST(ThreadExecutor, RealtimeRequestIsHonouredOrReportedRefused) {
  ThreadExecutor ex(ThreadExecutor::Options{true});
  Counter c;
  ex.attach(c, {3, 0ms, "rt"});
  ASSERT_TRUE(eventually([&] { return c.started.load(); }));
  // Either the OS granted SCHED_FIFO or the executor says it fell back; both are legal here,
  // but the flag must agree with what a fresh thread is allowed to do.
  sched_param sp{};
  sp.sched_priority = 1;
  pthread_t self = pthread_self();
  int old_policy = 0;
  sched_param old{};
  pthread_getschedparam(self, &old_policy, &old);
  const bool permitted = pthread_setschedparam(self, SCHED_FIFO, &sp) == 0;
  if (permitted) pthread_setschedparam(self, old_policy, &old);
  EXPECT_EQ(ex.realtime_active(), permitted);
  c.slot->detach();
  ASSERT_TRUE(eventually([&] { return c.released.load(); }));
}

}  // namespace
}  // namespace symb::kernel
