#include "symb/kernel/lockstep_executor.hpp"

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <cstring>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "symb/kernel/virtual_time_executor.hpp"

namespace symb::kernel {
namespace {

using namespace std::chrono_literals;

// An activity whose handlers are whatever the test says, on any executor.
struct LockstepProbe final : Activity {
  explicit LockstepProbe(Executor& e) : exec(e) {}
  // Declared after its executor, a probe goes first: it detaches itself (outside a run that
  // stops and releases it at once).
  ~LockstepProbe() override {
    if (slot != nullptr && !released) slot->detach();
  }
  LockstepProbe(const LockstepProbe&) = delete;
  LockstepProbe& operator=(const LockstepProbe&) = delete;
  void on_activity_attached(ActivitySlot& s) override { slot = &s; }
  void on_activity_start() override {
    if (on_start) on_start();
  }
  void on_activity_input() override {
    if (on_input) on_input();
  }
  void on_activity_tick() override {
    if (on_tick) on_tick();
  }
  void on_activity_stop() override { stopped = true; }
  void on_activity_released() override { released = true; }
  std::int64_t now_ms() const { return exec.clock().now().count() / 1000000; }

  Executor& exec;
  ActivitySlot* slot = nullptr;
  std::function<void()> on_start, on_input, on_tick;
  bool stopped = false, released = false;
};

// A small swarm with the shape of a simulated one: a "world" on the main lane ticks every 30 ms
// (priority 100), reads every robot's command, moves the robots, and wakes each robot's
// controller with its new position; each robot's controller (on its lane) turns the position into
// the next command, and a second periodic task per robot (10 ms, offset phases) mixes its own
// state in. Returns a hash of everything the world saw.
struct MiniSwarm {
  struct Robot {
    double x = 0, command = 0, drift = 0;
    std::uint64_t seen = 0;
    std::unique_ptr<LockstepProbe> controller, wanderer;
  };
  std::vector<Robot> robots;
  std::unique_ptr<LockstepProbe> world;
  std::uint64_t hash = 1469598103934665603ull;

  void mix(double v) {
    std::uint64_t bits = 0;
    static_assert(sizeof bits == sizeof v);
    std::memcpy(&bits, &v, sizeof v);
    hash = (hash ^ bits) * 1099511628211ull;
  }

  MiniSwarm(Executor& main, std::size_t n) : robots(n) {
    world = std::make_unique<LockstepProbe>(main);
    world->on_tick = [this] {
      for (std::size_t i = 0; i < robots.size(); ++i) {
        Robot& r = robots[i];
        r.x += r.command * 0.03;
        // Robots repel their neighbour in index order: the world couples them.
        if (i + 1 < robots.size()) r.x -= 0.01 * (robots[i + 1].x - r.x);
        mix(r.x);
        mix(static_cast<double>(r.seen));
      }
      for (Robot& r : robots) r.controller->slot->wake();
    };
    for (std::size_t i = 0; i < n; ++i) {
      Robot& r = robots[i];
      Executor& lane = main.lane(i);
      r.controller = std::make_unique<LockstepProbe>(lane);
      r.controller->on_input = [&r, p = r.controller.get()] {
        ++r.seen;
        r.command = 1.0 - 0.1 * r.x + r.drift + 1e-3 * static_cast<double>(p->now_ms());
      };
      r.wanderer = std::make_unique<LockstepProbe>(lane);
      r.wanderer->on_tick = [&r, i] { r.drift = 0.5 * r.drift + 0.01 * static_cast<double>(i % 7) - 0.02; };
    }
    for (std::size_t i = 0; i < n; ++i) {
      Executor& lane = main.lane(i);
      lane.attach(*robots[i].controller, {2, Duration{0}, "controller"});
      lane.attach(*robots[i].wanderer, {1, Duration{std::chrono::milliseconds(7 + i % 5)}, "wanderer"});
    }
    main.attach(*world, {100, 30ms, "world"});
  }
};

std::uint64_t lockstep_swarm_hash(unsigned threads, std::size_t robots, Duration quantum = 30ms) {
  LockstepExecutor ex({.threads = threads, .quantum = quantum});
  MiniSwarm swarm(ex, robots);
  // Several calls, ending between and on world steps, as a run in slices does.
  ex.run_until(Time{1000ms});
  ex.run_until(Time{1020ms});
  ex.run_until(Time{3000ms});
  EXPECT_EQ(ex.now(), Time{3000ms});
  return swarm.hash;
}

TEST(LockstepExecutor, SameRunWithOneTwoAndFourThreads) {
  const std::uint64_t one = lockstep_swarm_hash(1, 64);
  EXPECT_EQ(lockstep_swarm_hash(2, 64), one);
  EXPECT_EQ(lockstep_swarm_hash(4, 64), one);
  // The quantum only bounds the windows: no quantum, or a shorter one, gives the same run.
  EXPECT_EQ(lockstep_swarm_hash(2, 64, Duration{0}), one);
  EXPECT_EQ(lockstep_swarm_hash(2, 64, 7ms), one);
  EXPECT_NE(lockstep_swarm_hash(1, 63), one);  // the hash does see the run
}

TEST(LockstepExecutor, SameRunAsTheVirtualTimeExecutor) {
  VirtualTimeExecutor single;
  MiniSwarm swarm(single, 64);
  single.run_until(Time{3000ms});
  EXPECT_EQ(lockstep_swarm_hash(1, 64), swarm.hash);
  EXPECT_EQ(lockstep_swarm_hash(2, 64), swarm.hash);
}

// Two lanes whose start handlers each wait for the other's to begin: both can only see it when
// the lanes run at once. Bounded waits, so a serial executor fails instead of hanging.
TEST(LockstepExecutor, LanesRunInParallel) {
  LockstepExecutor ex({.threads = 2, .quantum = 10ms});
  std::mutex mu;
  std::condition_variable cv;
  int started = 0;
  std::atomic<int> met{0};
  std::deque<LockstepProbe> probes;
  for (std::size_t i = 0; i < 2; ++i) {
    LockstepProbe& p = probes.emplace_back(ex.lane(i));
    p.on_start = [&] {
      std::unique_lock lock(mu);
      ++started;
      cv.notify_all();
      if (cv.wait_for(lock, 20s, [&] { return started == 2; })) met.fetch_add(1);
    };
    ex.lane(i).attach(p, {0, Duration{0}, "p"});
  }
  ex.run_until(Time{1ms});
  EXPECT_EQ(met.load(), 2);
}

// A cross-lane effect made by the main lane at a world step is seen by the lane at that instant,
// and what the lane does in reply is seen by the main lane's next step, never earlier.
TEST(LockstepExecutor, TheBarrierOrdersCrossLaneWork) {
  LockstepExecutor ex({.threads = 2, .quantum = 30ms});
  std::vector<std::string> log;  // only ever written by one thread at a time
  int reply = 0;
  LockstepProbe world(ex), robot(ex.lane(0));
  world.on_tick = [&] {
    log.push_back("world@" + std::to_string(world.now_ms()) + " sees " + std::to_string(reply));
    robot.slot->wake();
  };
  robot.on_input = [&] {
    reply = static_cast<int>(robot.now_ms());
    log.push_back("robot@" + std::to_string(robot.now_ms()));
  };
  ex.lane(0).attach(robot, {0, Duration{0}, "robot"});
  ex.attach(world, {100, 30ms, "world"});
  ex.run_until(Time{90ms});
  EXPECT_EQ(log, (std::vector<std::string>{"world@30 sees 0", "robot@30", "world@60 sees 30", "robot@60",
                                           "world@90 sees 60", "robot@90"}));
  EXPECT_EQ(ex.lane(0).clock().now(), Time{90ms});
  // Windows [0, 30), [30, 60), [60, 90), then the last one closing at 90 itself.
  EXPECT_EQ(ex.stats().windows, 4u);
  EXPECT_LE(ex.stats().lanes_wall, ex.stats().run_wall);
}

// Past the first windows only a sample of them is timed; the lanes' share is scaled up to every
// window. Here the lane's work (a spin of 200 us a window) is most of each window, but only about
// a fifth of the windows are timed (64 + 436 / 16 of 500): summed over those alone, the share
// would stay well under half.
TEST(LockstepExecutor, TheLanesShareIsEstimatedOverEveryWindow) {
  LockstepExecutor ex({.threads = 1, .quantum = 1ms});
  LockstepProbe world(ex), robot(ex.lane(0));
  world.on_tick = [&] { robot.slot->wake(); };
  robot.on_input = [] {
    const auto until = std::chrono::steady_clock::now() + 200us;
    while (std::chrono::steady_clock::now() < until) {
    }
  };
  ex.lane(0).attach(robot, {0, Duration{0}, "robot"});
  ex.attach(world, {100, 1ms, "world"});
  ex.run_until(Time{499ms});
  const LockstepExecutor::Stats s = ex.stats();
  ASSERT_EQ(s.windows, 500u);
  EXPECT_LE(s.lanes_wall, s.run_wall);
  EXPECT_GT(static_cast<double>(s.lanes_wall.count()), 0.5 * static_cast<double>(s.run_wall.count()));
}

TEST(LockstepExecutor, SuspendResumeDetachAndPriorityInsideALane) {
  LockstepExecutor ex({.threads = 2, .quantum = 10ms});
  std::vector<std::string> log;
  Executor& lane = ex.lane(3);
  EXPECT_EQ(ex.lane_count(), 4u);
  LockstepProbe lo(lane), hi(lane), boss(ex);
  lo.on_tick = [&] { log.push_back("lo@" + std::to_string(lo.now_ms())); };
  hi.on_tick = [&] {
    log.push_back("hi@" + std::to_string(hi.now_ms()));
    if (hi.now_ms() == 40) hi.slot->detach();  // from its own handler
  };
  boss.on_tick = [&] {
    // At a barrier, from the main lane: lanes are idle, their slots may be used directly.
    if (boss.now_ms() == 15) lo.slot->suspend();
    if (boss.now_ms() == 25) {
      lo.slot->resume();
      lo.slot->set_priority(9);
    }
  };
  lane.attach(lo, {1, 10ms, "lo"});
  lane.attach(hi, {5, 10ms, "hi"});
  ex.attach(boss, {100, 5ms, "boss"});
  ex.run_until(Time{50ms});
  // Higher priority first at one instant; lo is suspended from 15 to 25 ms, ticks again one period
  // after the resume (35 ms), now above hi; hi stops after its tick at 40.
  EXPECT_EQ(log, (std::vector<std::string>{"hi@10", "lo@10", "hi@20", "hi@30", "lo@35", "hi@40", "lo@45"}));
  EXPECT_TRUE(hi.stopped);
  EXPECT_TRUE(hi.released);
  EXPECT_FALSE(lo.stopped);
}

TEST(LockstepExecutor, InjectFromAForeignThreadIntoALane) {
  LockstepExecutor ex({.threads = 2, .quantum = 10ms});
  Executor& lane = ex.lane(1);
  (void)ex.lane(0);
  std::atomic<bool> ran{false};
  bool own_context = false;
  std::thread foreign([&] {
    EXPECT_FALSE(lane.on_own_context());
    lane.inject([&] {
      own_context = lane.on_own_context();
      ran = true;
    });
  });
  foreign.join();
  // Runs in the lane's next window.
  ex.run_for(10ms);
  EXPECT_TRUE(ran.load());
  EXPECT_TRUE(own_context);
  // And between runs, on the caller's thread.
  ran = false;
  std::thread([&] { lane.inject([&] { ran = true; }); }).join();
  EXPECT_EQ(ex.run_injected(), 1u);
  EXPECT_TRUE(ran.load());
}

// A main-lane handler stands in as every lane's own context (it runs while the lanes are idle);
// a lane's handler is its own lane's context and not another's.
TEST(LockstepExecutor, WhoIsOnWhoseContext) {
  LockstepExecutor ex({.threads = 2, .quantum = 10ms});
  Executor& a = ex.lane(0);
  Executor& b = ex.lane(1);
  std::atomic<int> checks{0};
  LockstepProbe world(ex), in_a(a);
  world.on_start = [&] {
    EXPECT_TRUE(ex.on_own_context());
    EXPECT_TRUE(a.on_own_context());
    EXPECT_TRUE(b.on_own_context());
    ++checks;
  };
  in_a.on_start = [&] {
    EXPECT_TRUE(a.on_own_context());
    EXPECT_FALSE(b.on_own_context());
    EXPECT_FALSE(ex.on_own_context());
    ++checks;
  };
  a.attach(in_a, {0, Duration{0}, "a"});
  ex.attach(world, {0, Duration{0}, "world"});
  EXPECT_FALSE(a.on_own_context());
  ex.run_until(Time{1ms});
  EXPECT_EQ(checks.load(), 2);
  EXPECT_FALSE(a.on_own_context());
}

TEST(LockstepExecutor, StopFromTheMainLaneReturnsAtThatInstant) {
  LockstepExecutor ex({.threads = 2, .quantum = 30ms});
  LockstepProbe world(ex), robot(ex.lane(0));
  int robot_ticks = 0;
  robot.on_tick = [&] { ++robot_ticks; };
  world.on_tick = [&] {
    if (world.now_ms() == 60) ex.stop();
  };
  ex.lane(0).attach(robot, {0, 10ms, "robot"});
  ex.attach(world, {100, 30ms, "world"});
  ex.run_until(Time{200ms});
  EXPECT_EQ(ex.now(), Time{60ms});
  EXPECT_EQ(robot_ticks, 5);  // 10..50: the window up to 60 ran, the instant 60 not yet
  ex.run_until(Time{100ms});
  EXPECT_EQ(robot_ticks, 10);
  EXPECT_EQ(ex.now(), Time{100ms});
}

TEST(LockstepExecutor, RunUntilIdleEndsWhenEveryLaneIsIdle) {
  LockstepExecutor ex({.threads = 2});
  LockstepProbe world(ex), a(ex.lane(0)), b(ex.lane(1));
  // A counter per lane: the two lanes run at the same time on the pool's two threads, and lanes
  // share nothing (the executor's contract).
  int a_inputs = 0, b_ticks = 0;
  // The main lane wakes a at 0; a at 0 does nothing more; b counts ticks to 5 then detaches.
  world.on_start = [&] { a.slot->wake(); };
  a.on_input = [&] { ++a_inputs; };
  b.on_tick = [&] {
    if (++b_ticks == 5) b.slot->detach();
  };
  ex.lane(0).attach(a, {0, Duration{0}, "a"});
  ex.lane(1).attach(b, {0, 20ms, "b"});
  ex.attach(world, {0, Duration{0}, "world"});
  ex.run_until_idle();
  EXPECT_EQ(a_inputs, 1);
  EXPECT_EQ(b_ticks, 5);
  EXPECT_EQ(ex.now(), Time{100ms});
  EXPECT_EQ(ex.pending_events(), 0u);
}

TEST(LockstepExecutor, WorkBesideTheLanesRunsInTheNextWindowAndBeforeReturning) {
  LockstepExecutor ex({.threads = 2, .quantum = 30ms});
  LockstepProbe world(ex), robot(ex.lane(0)), other(ex.lane(1));
  std::atomic<int> jobs{0};
  std::vector<int> seen_by_world;  // jobs done, as each world tick sees it
  world.on_tick = [&] {
    seen_by_world.push_back(jobs.load());
    // A job may not run on this context: the tick that asked for it must still see it undone.
    ex.run_alongside_lanes([&] { jobs.fetch_add(1); });
    EXPECT_EQ(jobs.load(), static_cast<int>(seen_by_world.size()) - 1);
    if (world.now_ms() == 90) ex.stop();
  };
  int robot_ticks = 0;
  robot.on_tick = [&] { ++robot_ticks; };
  ex.lane(0).attach(robot, {0, 10ms, "robot"});
  ex.lane(1).attach(other, {0, Duration{0}, "other"});
  ex.attach(world, {100, 30ms, "world"});
  ex.run_until(Time{200ms});
  // Each tick found the jobs of every earlier tick done: they ran in the windows between.
  EXPECT_EQ(seen_by_world, (std::vector<int>{0, 1, 2}));
  // The run stopped at 90 ms, before another window: the last job still ran before it returned.
  EXPECT_EQ(ex.now(), Time{90ms});
  EXPECT_EQ(jobs.load(), 3);
  EXPECT_EQ(robot_ticks, 8);

  // Every other executor runs the job at once.
  VirtualTimeExecutor plain;
  int ran = 0;
  plain.run_alongside_lanes([&] { ++ran; });
  EXPECT_EQ(ran, 1);
}

TEST(LockstepExecutor, CallsBeforeALanesWindowComeFirstInItOnItsThreadAndBeforeReturning) {
  LockstepExecutor ex({.threads = 2, .quantum = 30ms});
  LockstepProbe world(ex), first(ex.lane(0)), second(ex.lane(1));
  // lane() is the executor's thread's to call (not a lane's, during its window): taken here.
  Executor* const lanes[2] = {&ex.lane(0), &ex.lane(1)};
  // What each lane saw, in its own order: "call@ms" for a call made for it, "tick@ms" for its tick.
  std::vector<std::string> seen[2];
  std::atomic<int> calls_off_context{0};
  std::vector<int> undone_when_asked;  // calls not yet made when the world tick asked for them
  std::atomic<int> made{0};
  world.on_tick = [&] {
    const std::int64_t at = world.now_ms();
    const int before = made.load();
    // Three indices, two lanes: the one without a lane is called at once, here.
    ex.for_each_lane_before_its_window(3, [&, at](std::size_t i) {
      made.fetch_add(1);
      if (i < 2) {
        if (!lanes[i]->on_own_context()) calls_off_context.fetch_add(1);
        seen[i].push_back("call@" + std::to_string(at));
      }
    });
    undone_when_asked.push_back(made.load() - before);
    if (at == 60) ex.stop();
  };
  first.on_tick = [&] { seen[0].push_back("tick@" + std::to_string(first.now_ms())); };
  second.on_tick = [&] { seen[1].push_back("tick@" + std::to_string(second.now_ms())); };
  ex.lane(0).attach(first, {0, 30ms, "first"});
  ex.lane(1).attach(second, {0, 30ms, "second"});
  ex.attach(world, {100, 30ms, "world"});
  ex.run_until(Time{200ms});
  // Only index 2 was called in the world's tick; lanes 0 and 1 waited for their window, where
  // their call came before their own tick at the same instant, on the lane's own context.
  // The world ticks at 30 and 60 ms.
  EXPECT_EQ(undone_when_asked, (std::vector<int>{1, 1}));
  const std::vector<std::string> expected{"call@30", "tick@30", "call@60"};
  EXPECT_EQ(seen[0], expected);
  EXPECT_EQ(seen[1], expected);
  // The run stopped at 60 ms, before another window: the calls of that tick were made before it
  // returned (the lanes' own ticks at 60 belong to a window that never came).
  EXPECT_EQ(made.load(), 6);
  EXPECT_EQ(calls_off_context.load(), 0);

  // Outside a run, and on every other executor, the calls are made at once.
  ex.for_each_lane_before_its_window(2, [&](std::size_t) { made.fetch_add(1); });
  EXPECT_EQ(made.load(), 8);
  VirtualTimeExecutor plain;
  int ran = 0;
  plain.for_each_lane_before_its_window(2, [&](std::size_t) { ++ran; });
  EXPECT_EQ(ran, 2);
}

}  // namespace
}  // namespace symb::kernel
