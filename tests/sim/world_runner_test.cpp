#include "symb/sim/world_runner.hpp"

#include <chrono>
#include <mutex>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "symb/kernel/lockstep_executor.hpp"
#include "symb/kernel/thread_executor.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/robot/actuator.hpp"
#include "symb/robot/ports.hpp"
#include "symb/robot/sensor.hpp"
#include "symb/sim/enki_world.hpp"
#include "symb/sim/sim_drivers.hpp"

#include "support/eventually.hpp"

namespace symb::sim {
namespace {

using namespace std::chrono_literals;
constexpr kernel::Duration kPeriod = 30ms;

// A controller whose command says which IR sample it answers: for the sample sent at step k
// (time k * period) it drives both wheels at (k mod 50) * 10 motor units, unless `constant` is
// set. It remembers what it saw.
class StampController final : public os::Task {
 public:
  struct Seen {
    kernel::Time message_time{0};
    kernel::Time handled_at{0};
    IrReadings ir{};
  };
  explicit StampController(float constant = -1) : constant_(constant) {}

  std::vector<Seen> seen() const {
    std::lock_guard lock(mu_);
    return seen_;
  }

 protected:
  void on_message(const os::Message& m) override {
    if (m.port != robot::kDataPort || m.numbers().size() != kIrCount) return;
    Seen s{m.time, now(), {}};
    std::copy(m.numbers().begin(), m.numbers().end(), s.ir.begin());
    {
      std::lock_guard lock(mu_);
      seen_.push_back(s);
    }
    float u = constant_;
    if (u < 0) u = static_cast<float>((m.time / kPeriod) % 50 * 10);
    send(robot::kDataPort, {u, u});
  }

 private:
  float constant_;
  mutable std::mutex mu_;
  std::vector<Seen> seen_;
};

WorldSpec arena() {
  WorldSpec s;
  s.width = 400;
  s.height = 200;
  return s;
}

// One robot's node: ir (SensorTask) -> controller -> wheels (ActuatorSinkTask).
struct Robot {
  Robot(kernel::Executor& ex, WorldRunner& runner, std::size_t i, float constant = -1) : node(ex, {"bot"}) {
    auto c = std::make_unique<StampController>(constant);
    controller = c.get();
    const auto ir = *node.create("ir", std::make_unique<robot::SensorTask>(runner.ir_sensor(i)));
    const auto ctl = *node.create("controller", std::move(c));
    const auto wheels = *node.create("wheels", std::make_unique<robot::ActuatorSinkTask>(runner.wheels(i)));
    EXPECT_TRUE(node.hook(ir, ctl));
    EXPECT_TRUE(node.hook(ctl, wheels));
  }
  os::Node node;
  StampController* controller = nullptr;
};

TEST(WorldRunner, IrToWheelsTakesExactlyOneControlPeriodUnderVirtualTime) {
  kernel::VirtualTimeExecutor ex;
  EnkiWorld world(arena(), 1);
  world.add_robot("bot", RobotKind::kThymio2, {50, 100, 0});
  WorldRunner runner(ex, world);
  Robot bot(ex, runner, 0);
  std::vector<StepRecord> records;
  runner.add_observer([&](const StepRecord& r) { records.push_back(r); });
  ASSERT_TRUE(runner.start());
  ex.run_for(3s);

  ASSERT_EQ(records.size(), 100u);
  EXPECT_EQ(runner.steps(), 100u);
  for (std::size_t i = 0; i < records.size(); ++i) {
    const StepRecord& r = records[i];
    const std::uint64_t step = i + 1;
    ASSERT_EQ(r.step, step);
    ASSERT_EQ(r.time, kernel::Time{kPeriod * static_cast<long>(step)});
    // Step s drives with the answer to the IR of step s - 1 (none for step 1).
    const double expected = step == 1 ? 0.0 : wheel_units_to_cm_per_s(static_cast<float>((step - 1) % 50 * 10));
    ASSERT_DOUBLE_EQ(r.robots[0].state.left_speed, expected) << "step " << step;
    ASSERT_DOUBLE_EQ(r.robots[0].state.right_speed, expected) << "step " << step;
  }
  // Every sample reached the controller at the instant it was published, with the values the
  // world gave for that step.
  const auto seen = bot.controller->seen();
  ASSERT_EQ(seen.size(), records.size());
  for (std::size_t i = 0; i < seen.size(); ++i) {
    EXPECT_EQ(seen[i].message_time, records[i].time);
    EXPECT_EQ(seen[i].handled_at, records[i].time);
    EXPECT_EQ(seen[i].ir, records[i].robots[0].ir);
  }
  // The robot drove (at about 8 cm/s on average), straight ahead.
  const RobotState end = records.back().robots[0].state;
  EXPECT_GT(end.distance, 15.0);
  EXPECT_NEAR(end.pose.x - 50, end.distance, 1.0);
  EXPECT_EQ(runner.wheels(0)->command().sequence, 100u);
}

// Counts what it is sent (a task hooked to a pose or ground sensor task).
class Counting final : public os::Task {
 public:
  std::size_t count = 0;
  std::vector<float> last;

 protected:
  void on_message(const os::Message& m) override {
    ++count;
    last.assign(m.numbers().begin(), m.numbers().end());
  }
};

// Publishing a pose or a ground reading costs a lock and a copy per robot and step, so the runner
// publishes to those sensors only while a task listens: it follows a task's start and removal,
// and a sensor a task still holds outlives the runner.
TEST(WorldRunner, PublishesPoseAndGroundOnlyWhileATaskListens) {
  kernel::VirtualTimeExecutor ex;
  EnkiWorld world(arena(), 1);
  world.add_robot("bot", RobotKind::kThymio2, {50, 100, 0});
  auto runner = std::make_unique<WorldRunner>(ex, world);
  const std::shared_ptr<SimPoseSensor> pose = runner->pose_sensor(0);
  const std::shared_ptr<SimGroundSensor> ground = runner->ground_sensor(0);
  ASSERT_TRUE(runner->start());
  ex.run_for(90ms);
  EXPECT_FALSE(pose->latest()) << "nobody listens: nothing published";
  EXPECT_FALSE(ground->latest());

  os::Node node(ex, {"bot"});
  auto c = std::make_unique<Counting>();
  Counting* counted = c.get();
  const auto pose_task = *node.create("pose", std::make_unique<robot::SensorTask>(pose));
  const auto sink = *node.create("sink", std::move(c));
  ASSERT_TRUE(node.hook(pose_task, sink));
  ex.run_for(90ms);
  EXPECT_EQ(counted->count, 3u);
  ASSERT_EQ(counted->last.size(), 3u);
  EXPECT_FLOAT_EQ(counted->last[0], 50.0f);
  EXPECT_FLOAT_EQ(counted->last[1], 100.0f);
  ASSERT_TRUE(pose->latest());
  EXPECT_EQ(pose->latest()->time, kernel::Time{180ms});
  EXPECT_FALSE(ground->latest()) << "the ground sensor still has no listener";

  ASSERT_TRUE(node.remove(pose_task));
  ex.run_for(90ms);
  EXPECT_EQ(pose->latest()->time, kernel::Time{180ms}) << "no listener again: nothing published";
  EXPECT_EQ(counted->count, 3u);

  // A task that holds the ground sensor when the runner goes, removed after it: its flag is shared.
  const auto ground_task = *node.create("ground", std::make_unique<robot::SensorTask>(ground));
  ex.run_for(30ms);
  ASSERT_TRUE(ground->latest());
  runner.reset();
  ASSERT_TRUE(node.remove(ground_task));
  ex.run_for(30ms);
  EXPECT_FALSE(ground->has_listener());
}

TEST(WorldRunner, StopsAndStartsAgain) {
  kernel::VirtualTimeExecutor ex;
  EnkiWorld world(arena(), 1);
  world.add_robot("a", RobotKind::kThymio2, {50, 100, 0});
  world.add_robot("b", RobotKind::kThymio2, {50, 50, 0});
  WorldRunner runner(ex, world, {.period = 10ms});
  ASSERT_EQ(runner.robot_count(), 2u);
  EXPECT_THROW((void)runner.ir_sensor(2), std::out_of_range);
  EXPECT_THROW((void)runner.wheels(2), std::out_of_range);
  ASSERT_TRUE(runner.start());
  EXPECT_FALSE(runner.start());  // already running
  ex.run_for(100ms);
  EXPECT_EQ(runner.steps(), 10u);
  runner.stop();
  EXPECT_FALSE(runner.running());
  ex.run_for(100ms);
  EXPECT_EQ(runner.steps(), 10u);
  EXPECT_EQ(runner.with_world([](World& w) { return w.steps(); }), 10u);
  ASSERT_TRUE(runner.start());
  ex.run_for(100ms);
  EXPECT_EQ(runner.steps(), 20u);
  EXPECT_TRUE(runner.error().empty());
}

TEST(WorldRunner, AnObserverThatThrowsStopsTheRunnerWithAnError) {
  kernel::VirtualTimeExecutor ex;
  EnkiWorld world(arena(), 1);
  world.add_robot("a", RobotKind::kThymio2, {50, 100, 0});
  WorldRunner runner(ex, world);
  runner.add_observer([](const StepRecord& r) {
    if (r.step == 3) throw std::runtime_error("disk full");
  });
  ASSERT_TRUE(runner.start());
  ex.run_for(1s);
  EXPECT_EQ(runner.steps(), 3u);
  EXPECT_FALSE(runner.running());
  EXPECT_NE(runner.error().find("disk full"), std::string::npos) << runner.error();
}

TEST(WorldRunner, RejectsABadPeriod) {
  kernel::VirtualTimeExecutor ex;
  EnkiWorld world(arena(), 1);
  EXPECT_THROW(WorldRunner(ex, world, {.period = 0ms}), std::invalid_argument);
  EXPECT_THROW(WorldRunner(ex, world, {.period = 2s}), std::invalid_argument);
}

// A robot's devices lock only where two threads may call them at once: under the thread executor.
// Under the virtual-time and lockstep executors every call comes from their contexts, one at a
// time, and the lock (a locked instruction per call, several calls a robot and step) is skipped.
TEST(WorldRunner, ItsDevicesLockOnlyUnderAConcurrentExecutor) {
  const auto threads_of = [](kernel::Executor& ex) {
    EnkiWorld world(arena(), 1);
    world.add_robot("a", RobotKind::kThymio2, {50, 100, 0});
    WorldRunner runner(ex, world);
    const std::vector<robot::DeviceThreads> t{runner.ir_sensor(0)->threads(), runner.wheels(0)->threads(),
                                              runner.pose_sensor(0)->threads(), runner.ground_sensor(0)->threads()};
    return t;
  };
  using robot::DeviceThreads;
  const std::vector<DeviceThreads> any(4, DeviceThreads::kAny), one(4, DeviceThreads::kOneAtATime);
  kernel::ThreadExecutor threads;
  EXPECT_EQ(threads_of(threads), any);
  kernel::VirtualTimeExecutor virtual_time;
  EXPECT_EQ(threads_of(virtual_time), one);
  kernel::LockstepExecutor lockstep({.threads = 2});
  EXPECT_EQ(threads_of(lockstep), one);
}

TEST(WorldRunner, DrivesRobotsUnderTheThreadExecutor) {
  kernel::ThreadExecutor ex;
  EnkiWorld world(arena(), 1);
  world.add_robot("a", RobotKind::kThymio2, {50, 100, 0});
  world.add_robot("b", RobotKind::kThymio2, {50, 50, 0});
  WorldRunner runner(ex, world, {.period = 5ms});
  std::atomic<std::uint64_t> observed{0};
  runner.add_observer([&](const StepRecord&) { observed.fetch_add(1); });
  {
    Robot a(ex, runner, 0, 400.0f);
    Robot b(ex, runner, 1, 200.0f);
    ASSERT_TRUE(runner.start());
    const auto deadline = std::chrono::steady_clock::now() + symb::testing::kEventuallyLimit;
    while ((runner.steps() < 40 || a.controller->seen().size() < 20 || b.controller->seen().size() < 20) &&
           std::chrono::steady_clock::now() < deadline) {
      // Reading the world while it steps on the runner's thread: with_world serialises.
      (void)runner.with_world([](World& w) { return w.state(0).distance; });
      std::this_thread::sleep_for(2ms);
    }
    runner.stop();
  }
  EXPECT_FALSE(runner.running());
  const std::uint64_t steps = runner.steps();
  EXPECT_GE(steps, 40u);
  EXPECT_EQ(observed.load(), steps);
  // Both robots drove, at their own speeds: a at 400 units, b at 200.
  const RobotState a = world.state(0), b = world.state(1);
  EXPECT_DOUBLE_EQ(a.left_speed, wheel_units_to_cm_per_s(400.0f));
  EXPECT_DOUBLE_EQ(b.left_speed, wheel_units_to_cm_per_s(200.0f));
  EXPECT_GT(a.distance, 0.0);
  EXPECT_GT(a.distance, b.distance);
  std::this_thread::sleep_for(20ms);
  EXPECT_EQ(runner.steps(), steps);  // stopped means stopped
}

}  // namespace
}  // namespace symb::sim
