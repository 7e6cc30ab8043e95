// kernel::RunWakesHere under the thread executor: a thread that wakes an idle activity runs its
// input handler itself, never beside another handler of it, losing no input and no tick; a busy,
// suspended, stopping, not yet started or realtime activity is only woken.
#include <atomic>
#include <barrier>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "symb/kernel/executor.hpp"
#include "symb/kernel/thread_executor.hpp"
#include "symb/kernel/virtual_time_executor.hpp"

#include "support/eventually.hpp"

namespace symb::kernel {
namespace run_wakes_here_test {  // named: the unity build shares one file's anonymous namespace
namespace {

using namespace std::chrono_literals;
using symb::testing::eventually;

// Counts its handlers, where they ran, and any two that overlapped. Input is "posted" by adding
// to `posted` before a wake; a handler takes all of it, as a task takes its whole queue.
struct Probe final : Activity {
  void on_activity_attached(ActivitySlot& s) override { slot = &s; }
  void on_activity_start() override {
    worker = std::this_thread::get_id();
    started.store(true);
    if (hold_start) hold_start();
  }
  void on_activity_input() override {
    enter();
    inputs.fetch_add(1);
    if (std::this_thread::get_id() != worker.load()) guest_inputs.fetch_add(1);
    handled.fetch_add(posted.exchange(0));
    if (during_input) during_input();
    leave();
  }
  void on_activity_tick() override {
    enter();
    ticks.fetch_add(1);
    leave();
  }
  void on_activity_stop() override {
    if (hold_stop) hold_stop();
  }
  void on_activity_released() override { released.store(true); }
  void enter() {
    if (in_handler.exchange(true)) overlaps.fetch_add(1);
    // Long enough that a handler started elsewhere meanwhile would be seen.
    for (int i = 0; i < 200; ++i) spin.fetch_add(1, std::memory_order_relaxed);
  }
  void leave() { in_handler.store(false); }

  ActivitySlot* slot = nullptr;
  std::atomic<std::thread::id> worker{};
  std::atomic<bool> started{false}, released{false}, in_handler{false};
  std::atomic<int> inputs{0}, guest_inputs{0}, ticks{0}, overlaps{0}, spin{0};
  std::atomic<long> posted{0}, handled{0};
  std::function<void()> hold_start, hold_stop, during_input;
};

// A gate a handler waits at until the test opens it.
struct Gate {
  void wait() {
    std::unique_lock lock(mu);
    reached = true;
    cv.notify_all();
    cv.wait(lock, [&] { return open; });
  }
  void wait_reached() {
    std::unique_lock lock(mu);
    cv.wait(lock, [&] { return reached; });
  }
  void release() {
    std::lock_guard lock(mu);
    open = true;
    cv.notify_all();
  }
  std::mutex mu;
  std::condition_variable cv;
  bool reached = false, open = false;
};

void stop(Probe& p) {
  p.slot->detach();
  ASSERT_TRUE(eventually([&] { return p.released.load(); }));
}

// Wakes `p` within a scope until the handler runs on this thread (the first tries may find the
// worker still finishing its start).
bool guest_runs(Probe& p) {
  const int before = p.guest_inputs.load();
  return eventually([&] {
    {
      RunWakesHere here;
      p.posted.fetch_add(1);
      p.slot->wake();
    }
    return p.guest_inputs.load() > before;
  });
}

TEST(RunWakesHere, IdleActivityRunsItsInputOnTheWakingThreadWhenTheScopeEnds) {
  ThreadExecutor ex;
  Probe p;
  ex.attach(p, {0, Duration{0}, "probe"});
  ASSERT_TRUE(guest_runs(p));
  const int inputs = p.inputs.load();
  {
    RunWakesHere here;
    p.posted.fetch_add(1);
    p.slot->wake();
    p.slot->wake();  // claimed already: one run takes both
    EXPECT_EQ(p.inputs.load(), inputs) << "the handler runs when the scope ends, not inside wake()";
  }
  EXPECT_EQ(p.inputs.load(), inputs + 1);
  EXPECT_EQ(p.posted.load(), 0) << "the run took what both wakes posted";
  stop(p);
  EXPECT_EQ(p.overlaps.load(), 0);
}

TEST(RunWakesHere, PlainWakesAndOtherExecutorsAreUnchanged) {
  ThreadExecutor ex;
  Probe p;
  ex.attach(p, {0, Duration{0}, "probe"});
  ASSERT_TRUE(eventually([&] { return p.started.load(); }));
  for (int i = 0; i < 20; ++i) {
    p.posted.fetch_add(1);
    p.slot->wake();  // no scope: its own thread handles it
  }
  ASSERT_TRUE(eventually([&] { return p.handled.load() == 20; }));
  EXPECT_EQ(p.guest_inputs.load(), 0);
  stop(p);

  // The virtual-time executor's slots keep the plain wake: input runs in its run, on its thread.
  VirtualTimeExecutor vt;
  Probe q;
  vt.attach(q, {0, Duration{0}, "probe"});
  vt.run_until_idle();
  {
    RunWakesHere here;
    q.posted.fetch_add(1);
    q.slot->wake();
  }
  EXPECT_EQ(q.inputs.load(), 0);
  vt.run_until_idle();
  EXPECT_EQ(q.inputs.load(), 1);
  EXPECT_EQ(q.handled.load(), 1);
  q.slot->detach();
  vt.run_until_idle();
  EXPECT_TRUE(q.released.load());
}

TEST(RunWakesHere, RealtimeExecutorOnlyWakes) {
  ThreadExecutor ex(ThreadExecutor::Options{.realtime = true});
  Probe p;
  ex.attach(p, {0, Duration{0}, "probe"});
  ASSERT_TRUE(eventually([&] { return p.started.load(); }));
  for (int i = 0; i < 20; ++i) {
    RunWakesHere here;
    p.posted.fetch_add(1);
    p.slot->wake();
  }
  ASSERT_TRUE(eventually([&] { return p.handled.load() == 20; }));
  EXPECT_EQ(p.guest_inputs.load(), 0);
  stop(p);
}

TEST(RunWakesHere, HandlersNeverOverlapAndNothingIsLostUnderManyWakingThreads) {
  ThreadExecutor ex;
  Probe p;
  ex.attach(p, {0, 1ms, "probe"});
  ASSERT_TRUE(guest_runs(p));
  ASSERT_TRUE(eventually([&] { return p.posted.load() == 0; }));
  const long base = p.handled.load();
  // Rounds of bursts from every thread at once; between rounds the activity runs dry, so that
  // each round begins with an idle activity that a guest may claim while others wake it.
  constexpr int kThreads = 4, kRounds = 150, kBurst = 8;
  std::atomic<long> sent{0};
  std::barrier burst_done(kThreads), caught_up(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t] {
      for (int r = 0; r < kRounds; ++r) {
        for (int i = 0; i < kBurst; ++i) {
          sent.fetch_add(1);
          p.posted.fetch_add(1);
          if ((i + t + r) % 3 == 0) {
            p.slot->wake();
          } else {
            RunWakesHere here;
            p.slot->wake();
          }
        }
        burst_done.arrive_and_wait();
        if (t == 0) {
          EXPECT_TRUE(eventually([&] { return p.handled.load() - base == sent.load(); }));
        }
        caught_up.arrive_and_wait();
      }
    });
  for (auto& t : threads) t.join();
  EXPECT_EQ(p.handled.load() - base, sent.load());
  stop(p);
  EXPECT_EQ(p.overlaps.load(), 0);
  EXPECT_GT(p.guest_inputs.load(), 10);
  EXPECT_GT(p.inputs.load() - p.guest_inputs.load(), 10) << "the activity's own thread took its share";
  EXPECT_GT(p.ticks.load(), 0);
}

TEST(RunWakesHere, InputArrivingDuringAGuestRunIsHandledByTheActivitysThread) {
  ThreadExecutor ex;
  Probe p;
  ex.attach(p, {0, Duration{0}, "probe"});
  ASSERT_TRUE(guest_runs(p));
  const auto me = std::this_thread::get_id();
  std::atomic<bool> once{true};
  std::atomic<std::thread::id> second{};
  p.during_input = [&] {
    if (std::this_thread::get_id() != me) {
      second.store(std::this_thread::get_id());
      return;
    }
    if (!once.exchange(false)) return;
    // Another thread posts meanwhile (its wake finds the activity busy), and so does this
    // handler, within a scope of its own: neither runs here nor is lost.
    std::thread([&] {
      p.posted.fetch_add(1);
      RunWakesHere there;
      p.slot->wake();
    }).join();
    RunWakesHere nested;
    p.posted.fetch_add(1);
    p.slot->wake();
  };
  const int inputs = p.inputs.load();
  {
    RunWakesHere here;
    p.posted.fetch_add(1);
    p.slot->wake();
  }
  ASSERT_TRUE(eventually([&] { return p.inputs.load() == inputs + 2 && p.posted.load() == 0; }));
  EXPECT_NE(second.load(), me);
  EXPECT_EQ(second.load(), p.worker.load());
  stop(p);
  EXPECT_EQ(p.overlaps.load(), 0);
}

TEST(RunWakesHere, SuspendedActivityIsOnlyWoken) {
  ThreadExecutor ex;
  Probe p;
  ex.attach(p, {0, Duration{0}, "probe"});
  ASSERT_TRUE(guest_runs(p));
  const int inputs = p.inputs.load();
  p.slot->suspend();
  {
    RunWakesHere here;
    p.posted.fetch_add(1);
    p.slot->wake();
  }
  std::this_thread::sleep_for(20ms);
  EXPECT_EQ(p.inputs.load(), inputs);
  p.slot->resume();
  ASSERT_TRUE(eventually([&] { return p.inputs.load() == inputs + 1; }));
  EXPECT_EQ(p.posted.load(), 0);
  stop(p);
}

TEST(RunWakesHere, ActivityNotYetStartedOrStoppingIsOnlyWoken) {
  ThreadExecutor ex;
  Probe p;
  Gate start, stopping;
  p.hold_start = [&] { start.wait(); };
  p.hold_stop = [&] { stopping.wait(); };
  ex.attach(p, {0, Duration{0}, "probe"});
  start.wait_reached();
  {
    RunWakesHere here;
    p.posted.fetch_add(1);
    p.slot->wake();
  }
  EXPECT_EQ(p.inputs.load(), 0) << "input ran before on_activity_start() returned";
  start.release();
  ASSERT_TRUE(eventually([&] { return p.inputs.load() == 1; }));
  EXPECT_EQ(p.guest_inputs.load(), 0);

  p.slot->detach();
  stopping.wait_reached();
  {
    RunWakesHere here;
    p.posted.fetch_add(1);
    p.slot->wake();
  }
  EXPECT_EQ(p.inputs.load(), 1) << "input ran after detach()";
  stopping.release();
  ASSERT_TRUE(eventually([&] { return p.released.load(); }));
  EXPECT_EQ(p.inputs.load(), 1);
}

TEST(RunWakesHere, TicksComeOnTimeWhileGuestsRunTheInput) {
  ThreadExecutor ex;
  Probe p;
  p.during_input = [] { std::this_thread::sleep_for(50us); };
  ex.attach(p, {0, 5ms, "probe"});
  ASSERT_TRUE(guest_runs(p));
  const int ticks = p.ticks.load();
  // Guests stream the input until 20 ticks came and over 100 inputs ran as guests: 100 ms on an
  // idle box (a tick held up by a guest comes as soon as its run ends, 50 us here). A loaded one
  // takes longer; a worker starved by the guests would never get there.
  const auto give_up = std::chrono::steady_clock::now() + symb::testing::kEventuallyLimit;
  while ((p.ticks.load() - ticks < 20 || p.guest_inputs.load() <= 100) && std::chrono::steady_clock::now() < give_up) {
    {
      RunWakesHere here;
      p.posted.fetch_add(1);
      p.slot->wake();
    }
    // A gap, or a worker that caught the stream keeps it (busy: it is only woken).
    std::this_thread::sleep_for(100us);
  }
  EXPECT_GE(p.ticks.load() - ticks, 20);
  EXPECT_GT(p.guest_inputs.load(), 100);
  stop(p);
  EXPECT_EQ(p.overlaps.load(), 0);
}

}  // namespace
}  // namespace run_wakes_here_test
}  // namespace symb::kernel
