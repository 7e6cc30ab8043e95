#include "symb/robot/actuator_task.hpp"

#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include "symb/kernel/thread_executor.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"

#include "fakes.hpp"
#include "support/eventually.hpp"

namespace symb::robot {
namespace {

using namespace std::chrono_literals;
using testing::Collector;
using testing::FakeDrive;
using testing::Plant;

constexpr double kPi = std::numbers::pi;
constexpr double kWheelBase = 0.1;

// A body (the plant, 100 Hz odometry) and an ActuatorTask (50 Hz) on one virtual-time node, with
// a collector for the task's status reports.
struct ActuatorRig {
  explicit ActuatorRig(ActuatorTask::Options o = {}, bool wheel_odometry = false) {
    o.wheel_base = kWheelBase;
    if (wheel_odometry) o.odometry = OdometryFormat::kWheelDistances;
    auto p = std::make_unique<Plant>(drive, kWheelBase, wheel_odometry);
    plant = p.get();
    plant_id = *node.create("body", std::move(p), {.priority = 2, .period = 10ms, .autostart = false});
    auto a = std::make_unique<ActuatorTask>(drive, o);
    task = a.get();
    id = *node.create("base", std::move(a), {.period = 20ms, .autostart = false});
    auto c = std::make_unique<Collector>();
    status = c.get();
    const auto status_id = *node.create("status", std::move(c));
    EXPECT_TRUE(node.hook(plant_id, id, {.policy = os::QueuePolicy::kKeepNewest}));
    EXPECT_TRUE(node.hook(id, status_id, {.policy = os::QueuePolicy::kRefuse, .port = kStatusPort}));
    EXPECT_TRUE(node.start(plant_id));
    EXPECT_TRUE(node.start(id));
    ex.run_for(0ms);
  }
  // Runs until a status with `event` arrives or `limit` of virtual time passed; returns it.
  std::optional<GoalStatus> run_until_event(GoalEvent event, kernel::Duration limit) {
    const kernel::Time end = ex.now() + limit;
    while (ex.now() < end) {
      ex.run_for(10ms);
      for (const auto& s : status->statuses())
        if (s.event == event) return s;
    }
    return std::nullopt;
  }
  kernel::Time time_of_first(GoalEvent event) const {
    for (const auto& r : status->received())
      if (auto s = decode_status(r.values); s && s->event == event) return r.time;
    return kernel::kTimeNever;
  }

  kernel::VirtualTimeExecutor ex;
  os::Node node{ex, {"bot"}};
  std::shared_ptr<FakeDrive> drive = std::make_shared<FakeDrive>(0.5);
  Plant* plant = nullptr;
  ActuatorTask* task = nullptr;
  Collector* status = nullptr;
  os::TaskId plant_id, id;
};

TEST(ActuatorTask, DrivesOneMetreAndReportsCompletion) {
  ActuatorRig rig;
  ASSERT_TRUE(ActuatorTask::command(rig.node, rig.id, DriveGoal::drive(1.0, 0.2, 7)));
  auto done = rig.run_until_event(GoalEvent::kCompleted, 10s);
  ASSERT_TRUE(done);
  EXPECT_EQ(done->id, 7u);
  EXPECT_EQ(done->kind, GoalKind::kDrive);
  EXPECT_EQ(done->reason, GoalReason::kNone);
  EXPECT_NEAR(done->achieved, 1.0, 0.005);
  EXPECT_NEAR(rig.plant->x(), 1.0, 0.01);
  EXPECT_NEAR(rig.plant->y(), 0.0, 1e-3);
  // 0.2 m/s for most of the way, then the proportional approach: about 6 s, on a tick.
  const kernel::Time at = rig.time_of_first(GoalEvent::kCompleted);
  EXPECT_GT(at, kernel::Time{5s});
  EXPECT_LT(at, kernel::Time{7s});
  EXPECT_EQ(at.count() % kernel::Time{20ms}.count(), 0);
  // Every command respected the goal's speed; the last one stopped the wheels.
  const auto cmds = rig.drive->commands();
  for (const auto& [l, r] : cmds) EXPECT_LE(std::max(std::abs(l), std::abs(r)), 0.2 + 1e-6);
  EXPECT_EQ(cmds.back(), (std::pair<double, double>{0, 0}));
  EXPECT_EQ(rig.drive->wheel_speeds(), (std::pair<double, double>{0, 0}));
  const auto st = rig.status->statuses();
  ASSERT_EQ(st.size(), 2u);
  EXPECT_EQ(st[0].event, GoalEvent::kAccepted);
  EXPECT_FALSE(rig.task->stats().busy);
  // It stays where it stopped.
  const double x = rig.plant->x();
  rig.ex.run_for(1s);
  EXPECT_EQ(rig.plant->x(), x);
}

// Whoever learns that a goal ended (a status listener, a thread polling stats()) must find the
// wheels already told to stop: the stop command comes before the count and the report.
TEST(ActuatorTask, TheWheelsAreStoppedBeforeTheGoalsEndIsCounted) {
  std::vector<ActuatorTaskStats> at_stop;  // outlives the rig: its node stops the wheels as it goes
  ActuatorRig rig;
  rig.drive->on_command = [&](double l, double r) {
    if (l == 0 && r == 0) at_stop.push_back(rig.task->stats());
  };
  ASSERT_TRUE(ActuatorTask::command(rig.node, rig.id, DriveGoal::drive(0.3, 0.2)));
  ASSERT_TRUE(rig.run_until_event(GoalEvent::kCompleted, 10s));
  ASSERT_EQ(at_stop.size(), 1u);
  EXPECT_EQ(at_stop[0].completed, 0u);
  EXPECT_EQ(rig.task->stats().completed, 1u);
  ASSERT_TRUE(ActuatorTask::command(rig.node, rig.id, DriveGoal::hold_speed(0.1)));
  rig.ex.run_for(200ms);
  ASSERT_TRUE(ActuatorTask::stop(rig.node, rig.id));
  ASSERT_TRUE(rig.run_until_event(GoalEvent::kAborted, 1s));
  ASSERT_EQ(at_stop.size(), 2u);
  EXPECT_EQ(at_stop[1].aborted, 0u);
  EXPECT_EQ(rig.task->stats().aborted, 1u);
}

TEST(ActuatorTask, TheSameGoalGivesTheSameRunBitForBit) {
  kernel::Time at[2];
  double x[2];
  for (int i = 0; i < 2; ++i) {
    ActuatorRig rig;
    ASSERT_TRUE(ActuatorTask::command(rig.node, rig.id, DriveGoal::drive(0.5, 0.25)));
    ASSERT_TRUE(rig.run_until_event(GoalEvent::kCompleted, 10s));
    at[i] = rig.time_of_first(GoalEvent::kCompleted);
    x[i] = rig.plant->x();
  }
  EXPECT_EQ(at[0], at[1]);
  EXPECT_EQ(x[0], x[1]);
}

TEST(ActuatorTask, TurnsNinetyDegreesInPlace) {
  ActuatorRig rig;
  ASSERT_TRUE(ActuatorTask::command(rig.node, rig.id, DriveGoal::turn(kPi / 2, 0.1)));
  auto done = rig.run_until_event(GoalEvent::kCompleted, 5s);
  ASSERT_TRUE(done);
  EXPECT_EQ(done->id, 1u);  // numbered by the task
  EXPECT_NEAR(done->achieved, kPi / 2, 0.01);
  EXPECT_NEAR(rig.plant->theta(), kPi / 2, 0.015);
  EXPECT_NEAR(rig.plant->x(), 0.0, 1e-9);
  EXPECT_NEAR(rig.plant->y(), 0.0, 1e-9);
  EXPECT_LT(rig.time_of_first(GoalEvent::kCompleted), kernel::Time{3s});
  EXPECT_EQ(rig.drive->wheel_speeds(), (std::pair<double, double>{0, 0}));
}

TEST(ActuatorTask, TurnsOneAndAHalfTurnsClockwiseThroughTheWrapOfThePose) {
  ActuatorRig rig;
  ASSERT_TRUE(ActuatorTask::command(rig.node, rig.id, DriveGoal::turn(-3 * kPi, 0.2)));
  auto done = rig.run_until_event(GoalEvent::kCompleted, 10s);
  ASSERT_TRUE(done);
  EXPECT_NEAR(rig.plant->theta(), -3 * kPi, 0.015);
}

TEST(ActuatorTask, DrivesWithWheelDistanceOdometry) {
  ActuatorRig rig({}, /*wheel_odometry=*/true);
  ASSERT_TRUE(ActuatorTask::command(rig.node, rig.id, DriveGoal::drive(-0.3, 0.15)));
  auto done = rig.run_until_event(GoalEvent::kCompleted, 10s);
  ASSERT_TRUE(done);
  EXPECT_NEAR(rig.plant->x(), -0.3, 0.01);
  ASSERT_TRUE(ActuatorTask::command(rig.node, rig.id, DriveGoal::turn(kPi, 0.1)));
  for (int i = 0; i < 500 && rig.task->stats().completed < 2; ++i) rig.ex.run_for(10ms);
  EXPECT_EQ(rig.task->stats().completed, 2u);
  EXPECT_NEAR(rig.plant->theta(), kPi, 0.015);
}

TEST(ActuatorTask, ANewGoalAbortsTheOldOneWithAStatus) {
  ActuatorRig rig;
  ASSERT_TRUE(ActuatorTask::command(rig.node, rig.id, DriveGoal::drive(1.0, 0.2, 1)));
  rig.ex.run_for(1s);
  ASSERT_TRUE(ActuatorTask::command(rig.node, rig.id, DriveGoal::turn(kPi / 2, 0.1, 2)));
  ASSERT_TRUE(rig.run_until_event(GoalEvent::kCompleted, 5s));
  const auto st = rig.status->statuses();
  ASSERT_EQ(st.size(), 4u);
  EXPECT_EQ(st[0].event, GoalEvent::kAccepted);
  EXPECT_EQ(st[0].id, 1u);
  EXPECT_EQ(st[1].event, GoalEvent::kAborted);
  EXPECT_EQ(st[1].id, 1u);
  EXPECT_EQ(st[1].reason, GoalReason::kReplaced);
  EXPECT_NEAR(st[1].achieved, 0.2, 0.01);  // one second at 0.2 m/s
  EXPECT_EQ(st[2].event, GoalEvent::kAccepted);
  EXPECT_EQ(st[2].id, 2u);
  EXPECT_EQ(st[3].event, GoalEvent::kCompleted);
  EXPECT_EQ(st[3].id, 2u);
  // The abort and the new acceptance happen at the instant the new goal arrived.
  const auto got = rig.status->received();
  EXPECT_EQ(got[1].time, kernel::Time{1s});
  EXPECT_EQ(got[2].time, kernel::Time{1s});
  EXPECT_EQ(rig.task->stats().aborted, 1u);
}

TEST(ActuatorTask, SilentOdometryStopsTheWheels) {
  ActuatorRig rig;
  ASSERT_TRUE(ActuatorTask::command(rig.node, rig.id, DriveGoal::drive(1.0, 0.2)));
  rig.ex.run_for(1s);
  EXPECT_NE(rig.drive->wheel_speeds().first, 0.0);
  ASSERT_TRUE(rig.node.suspend(rig.plant_id));  // the last odometry was sent at 1 s
  auto aborted = rig.run_until_event(GoalEvent::kAborted, 1s);
  ASSERT_TRUE(aborted);
  EXPECT_EQ(aborted->reason, GoalReason::kOdometryTimeout);
  // Silent for more than 200 ms first at the tick of 1.22 s.
  EXPECT_EQ(rig.time_of_first(GoalEvent::kAborted), kernel::Time{1220ms});
  EXPECT_EQ(rig.drive->wheel_speeds(), (std::pair<double, double>{0, 0}));
  EXPECT_EQ(rig.task->stats().timeouts, 1u);
  bool warned = false;
  for (const auto& e : rig.node.log().since(0))
    if (e.level == os::LogLevel::kWarn && e.text.find("no odometry") != std::string::npos) warned = true;
  EXPECT_TRUE(warned);
}

TEST(ActuatorTask, AGoalWithoutAnyOdometryNeverMovesTheWheels) {
  ActuatorRig rig;
  ASSERT_TRUE(rig.node.suspend(rig.plant_id));
  rig.ex.run_for(1s);
  ASSERT_TRUE(ActuatorTask::command(rig.node, rig.id, DriveGoal::drive(1.0, 0.2)));
  ASSERT_TRUE(rig.run_until_event(GoalEvent::kAborted, 1s));
  for (const auto& [l, r] : rig.drive->commands()) EXPECT_EQ(std::make_pair(l, r), std::make_pair(0.0, 0.0));
}

TEST(ActuatorTask, StopZeroesTheWheelsAtOnce) {
  ActuatorRig rig;
  ASSERT_TRUE(ActuatorTask::command(rig.node, rig.id, DriveGoal::hold_speed(0.15, 9)));
  rig.ex.run_for(1s);
  // Goals travel as floats: 0.15 arrives as 0.15f.
  EXPECT_EQ(rig.drive->wheel_speeds(), (std::pair<double, double>{0.15f, 0.15f}));
  ASSERT_TRUE(ActuatorTask::stop(rig.node, rig.id));
  rig.ex.run_for(0ms);
  EXPECT_EQ(rig.drive->wheel_speeds(), (std::pair<double, double>{0, 0}));
  const auto st = rig.status->statuses();
  ASSERT_EQ(st.size(), 2u);
  EXPECT_EQ(st[1].event, GoalEvent::kAborted);
  EXPECT_EQ(st[1].reason, GoalReason::kStopped);
  EXPECT_EQ(st[1].id, 9u);
  EXPECT_NEAR(st[1].achieved, 0.15, 0.01);
  EXPECT_EQ(rig.status->received()[1].time, kernel::Time{1s});
  // With no goal, stop still zeroes whatever else set the wheels.
  ASSERT_TRUE(rig.drive->set_wheel_speeds(0.3, 0.3));
  ASSERT_TRUE(ActuatorTask::stop(rig.node, rig.id));
  rig.ex.run_for(0ms);
  EXPECT_EQ(rig.drive->wheel_speeds(), (std::pair<double, double>{0, 0}));
}

TEST(ActuatorTask, DeletingTheTaskStopsTheWheels) {
  ActuatorRig rig;
  ASSERT_TRUE(ActuatorTask::command(rig.node, rig.id, DriveGoal::hold_speed(0.1)));
  rig.ex.run_for(500ms);
  EXPECT_NE(rig.drive->wheel_speeds().first, 0.0);
  ASSERT_TRUE(rig.node.remove(rig.id));
  EXPECT_EQ(rig.drive->wheel_speeds(), (std::pair<double, double>{0, 0}));
}

TEST(ActuatorTask, BadGoalsAreRejectedAndTheGoalInProgressGoesOn) {
  ActuatorRig rig;
  ASSERT_TRUE(ActuatorTask::command(rig.node, rig.id, DriveGoal::drive(0.5, 0.2, 1)));
  rig.ex.run_for(100ms);
  ASSERT_TRUE(ActuatorTask::command(rig.node, rig.id, DriveGoal::drive(1, 0, 2)));  // no speed
  ASSERT_TRUE(ActuatorTask::command(rig.node, rig.id, DriveGoal::turn(1, -0.1, 3)));
  os::Message nan;
  nan.port = kCommandPort;
  nan.payload = os::Payload{1, std::numeric_limits<float>::quiet_NaN(), 0.1f, 4};
  ASSERT_TRUE(rig.node.post(rig.id, nan));
  os::Message junk;
  junk.port = kCommandPort;
  junk.payload = os::Payload{42};
  ASSERT_TRUE(rig.node.post(rig.id, junk));
  rig.ex.run_for(0ms);
  auto done = rig.run_until_event(GoalEvent::kCompleted, 10s);
  ASSERT_TRUE(done);
  EXPECT_EQ(done->id, 1u);
  std::vector<std::uint32_t> rejected;
  for (const auto& s : rig.status->statuses())
    if (s.event == GoalEvent::kRejected) {
      EXPECT_EQ(s.reason, GoalReason::kBadGoal);
      rejected.push_back(s.id);
    }
  EXPECT_EQ(rejected, (std::vector<std::uint32_t>{2, 3, 4, 0}));
  EXPECT_EQ(rig.task->stats().rejected, 4u);
}

TEST(ActuatorTask, SpeedsAboveTheLimitAreClampedWithAWarning) {
  ActuatorTask::Options o;
  o.max_speed = 0.3;
  ActuatorRig rig(o);
  ASSERT_TRUE(ActuatorTask::command(rig.node, rig.id, DriveGoal::drive(0.5, 5.0)));
  ASSERT_TRUE(rig.run_until_event(GoalEvent::kCompleted, 10s));
  for (const auto& [l, r] : rig.drive->commands()) EXPECT_LE(std::max(std::abs(l), std::abs(r)), 0.3 + 1e-6);
  bool warned = false;
  for (const auto& e : rig.node.log().since(0))
    if (e.text.find("clamped to the limit 0.3") != std::string::npos) warned = true;
  EXPECT_TRUE(warned);
}

TEST(ActuatorTask, ADriveThatRefusesCommandsAbortsTheGoal) {
  ActuatorRig rig;
  ASSERT_TRUE(ActuatorTask::command(rig.node, rig.id, DriveGoal::drive(1.0, 0.2)));
  rig.ex.run_for(200ms);
  rig.drive->fail = true;
  auto aborted = rig.run_until_event(GoalEvent::kAborted, 1s);
  ASSERT_TRUE(aborted);
  EXPECT_EQ(aborted->reason, GoalReason::kDriveError);
  EXPECT_GE(rig.task->stats().drive_errors, 1u);
}

// Sends one goal on the command port when it starts: a controller that commands through hooks.
class GoalSender : public os::Task {
 public:
  explicit GoalSender(DriveGoal g) : goal_(g) {}

 protected:
  void on_start() override { send(kCommandPort, encode_goal(goal_)); }

 private:
  DriveGoal goal_;
};

TEST(ActuatorTask, TakesGoalsFromHookedTasks) {
  ActuatorRig rig;
  auto sender = *rig.node.create("planner", std::make_unique<GoalSender>(DriveGoal::turn(-kPi / 2, 0.1, 5)),
                                 {.autostart = false});
  ASSERT_TRUE(rig.node.hook(sender, rig.id, {.policy = os::QueuePolicy::kRefuse}));
  ASSERT_TRUE(rig.node.start(sender));
  auto done = rig.run_until_event(GoalEvent::kCompleted, 5s);
  ASSERT_TRUE(done);
  EXPECT_EQ(done->id, 5u);
  EXPECT_NEAR(rig.plant->theta(), -kPi / 2, 0.015);
}

TEST(ActuatorTask, DrivesUnderThreads) {
  kernel::ThreadExecutor ex;
  os::Node node(ex, {"bot"});
  auto drive = std::make_shared<FakeDrive>(0.5);
  ActuatorTask::Options o;
  o.wheel_base = kWheelBase;
  o.odometry_timeout = 2s;  // a loaded machine may stall a thread for a while; that is not this test
  auto p = std::make_unique<Plant>(drive, kWheelBase);
  Plant* plant = p.get();
  auto body = *node.create("body", std::move(p), {.priority = 2, .period = 10ms, .autostart = false});
  auto a = std::make_unique<ActuatorTask>(drive, o);
  ActuatorTask* task = a.get();
  auto base = *node.create("base", std::move(a), {.period = 20ms, .autostart = false});
  ASSERT_TRUE(node.hook(body, base));
  ASSERT_TRUE(node.start(body));
  ASSERT_TRUE(node.start(base));
  std::this_thread::sleep_for(50ms);  // odometry flows
  ASSERT_TRUE(ActuatorTask::command(node, base, DriveGoal::drive(0.2, 0.3)));
  EXPECT_TRUE(symb::testing::eventually([&] { return task->stats().completed == 1; }));
  EXPECT_NEAR(plant->x(), 0.2, 0.03);  // real time jitters; the loop still closes
  EXPECT_EQ(drive->wheel_speeds(), (std::pair<double, double>{0, 0}));
  ASSERT_TRUE(ActuatorTask::command(node, base, DriveGoal::hold_speed(0.1)));
  EXPECT_TRUE(symb::testing::eventually([&] { return drive->wheel_speeds().first != 0.0; }));
  ASSERT_TRUE(ActuatorTask::stop(node, base));
  EXPECT_TRUE(symb::testing::eventually([&] { return drive->wheel_speeds() == std::pair<double, double>{0, 0}; }));
}

TEST(ActuatorTask, RefusesOptionsThatMakeNoSense) {
  auto drive = std::make_shared<FakeDrive>();
  ActuatorTask::Options o;
  o.command_port = o.odometry_port;
  EXPECT_THROW(ActuatorTask(drive, o), std::invalid_argument);
  o = {};
  o.wheel_base = 0;
  EXPECT_THROW(ActuatorTask(drive, o), std::invalid_argument);
  o = {};
  o.kp_turn = -1;
  EXPECT_THROW(ActuatorTask(drive, o), std::invalid_argument);
  EXPECT_THROW(ActuatorTask(nullptr, {}), std::invalid_argument);
  EXPECT_THROW(FakeDrive(0), std::invalid_argument);
}

TEST(DifferentialDrive, ClampsAndRefusesNaN) {
  FakeDrive d(0.5);
  EXPECT_FALSE(d.set_wheel_speeds(0.1, 0.1));  // closed
  ASSERT_TRUE(d.open());
  ASSERT_TRUE(d.set_wheel_speeds(1.0, -2.0));
  EXPECT_EQ(d.wheel_speeds(), (std::pair<double, double>{0.5, -0.5}));
  EXPECT_FALSE(d.set_wheel_speeds(std::nan(""), 0));
  EXPECT_EQ(d.wheel_speeds(), (std::pair<double, double>{0.5, -0.5}));
  EXPECT_EQ(*d.ioctl("speeds"), "0.5 -0.5");
  EXPECT_EQ(*d.ioctl("stop"), "0 0");
  const DriveStats s = d.stats();
  EXPECT_EQ(s.commands, 4u);
  EXPECT_EQ(s.applied, 2u);
  EXPECT_EQ(s.rejected, 2u);
  EXPECT_EQ(s.clamped, 1u);
}

}  // namespace
}  // namespace symb::robot
