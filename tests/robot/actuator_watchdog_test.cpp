// The actuator sink's watchdog: a silent controller (suspended, deleted) means the wheels stop
// within timeout + the sink's period, once per silence, and the next command drives them again.
#include <gtest/gtest.h>

#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/robot/actuator.hpp"
#include "symb/robot/robot_task_types.hpp"

#include "fakes.hpp"

namespace symb::robot {
namespace {

using namespace std::chrono_literals;

// Two wheels (-500..500) and, to show "closest to 0", a pump that only runs between 100 and 200
// and a valve held between -300 and -50. Remembers each command with its virtual time.
class RecordingMotors final : public Actuator {
 public:
  explicit RecordingMotors(const kernel::VirtualTimeExecutor& ex)
      : Actuator("motors",
                 {{"left", "", -500, 500}, {"right", "", -500, 500}, {"pump", "", 100, 200}, {"valve", "", -300, -50}}),
        ex_(ex) {}
  struct Applied {
    kernel::Time time;
    std::vector<float> values;
  };
  std::vector<Applied> applied;

 protected:
  kernel::Status apply(std::span<const float> v) override {
    applied.push_back({ex_.now(), {v.begin(), v.end()}});
    return {};
  }

 private:
  const kernel::VirtualTimeExecutor& ex_;
};

// A controller that sends the same command at each of its ticks.
class Driver : public os::Task {
 public:
  explicit Driver(std::vector<float> command) : command_(std::move(command)) {}

 protected:
  void on_tick() override { send(kDataPort, command_); }

 private:
  std::vector<float> command_;
};

const std::vector<float> kDrive{120, 120, 150, -100};
const std::vector<float> kSafe{0, 0, 100, -50};

// The robot's task types, with `motors` the one actuator they can name.
struct MotorTypes {
  explicit MotorTypes(const std::shared_ptr<RecordingMotors>& motors) {
    RobotDevices devices;
    devices.actuator = [motors](std::string_view n) -> std::shared_ptr<Actuator> {
      return n == "motors" ? motors : nullptr;
    };
    registered = register_robot_task_types(registry, std::move(devices));
  }
  os::TaskTypeRegistry registry;
  kernel::Status registered;
};

std::size_t warnings_containing(os::Node& node, std::string_view text) {
  std::size_t n = 0;
  for (const auto& e : node.log().since(0))
    if (e.level == os::LogLevel::kWarn && e.text.find(text) != std::string::npos) ++n;
  return n;
}

TEST(ActuatorWatchdog, SuspendedControllerStopsTheWheelsWithinTwoControlPeriods) {
  kernel::VirtualTimeExecutor ex;
  os::Node node(ex, {"bot"});
  auto motors = std::make_shared<RecordingMotors>(ex);
  ActuatorSinkTask::Options o;
  o.timeout = 45ms;
  auto sink_task = std::make_unique<ActuatorSinkTask>(motors, o);
  ActuatorSinkTask* sink = sink_task.get();
  auto sink_id = *node.create("wheels", std::move(sink_task), {.period = 10ms});
  auto ctl = *node.create("ctl", std::make_unique<Driver>(kDrive), {.priority = 2, .period = 30ms});
  ASSERT_TRUE(node.hook(ctl, sink_id));

  ex.run_until(kernel::Time{400ms});
  EXPECT_EQ(sink->stats().timeouts, 0u);  // commands every 30 ms never let 45 ms pass
  EXPECT_EQ(motors->output(), kDrive);
  const kernel::Time last_command = motors->applied.back().time;
  EXPECT_EQ(last_command, kernel::Time{390ms});

  // Suspended between two of its ticks: the last command was at 390 ms.
  ex.run_until(kernel::Time{405ms});
  const kernel::Time suspended_at = ex.now();
  ASSERT_TRUE(node.suspend(ctl));
  ex.run_until(kernel::Time{600ms});
  EXPECT_EQ(sink->stats().timeouts, 1u);  // once per silence, not at every tick
  EXPECT_EQ(motors->output(), kSafe);
  const auto& stop = motors->applied.back();
  EXPECT_EQ(stop.values, kSafe);
  EXPECT_GE(stop.time - last_command, 45ms);
  EXPECT_LE(stop.time - suspended_at, 60ms);  // two control periods
  EXPECT_EQ(stop.time, kernel::Time{440ms});  // the first sink tick at least 45 ms after 390 ms
  EXPECT_EQ(warnings_containing(node, "timeout"), 1u);

  // Resumed: its next command is applied as usual, and the watchdog is armed again.
  const std::size_t before = motors->applied.size();
  ASSERT_TRUE(node.resume(ctl));
  ex.run_until(kernel::Time{800ms});
  ASSERT_GT(motors->applied.size(), before);
  EXPECT_EQ(motors->applied[before].values, kDrive);
  EXPECT_EQ(motors->output(), kDrive);
  EXPECT_EQ(sink->stats().timeouts, 1u);

  // Deleted: the same stop.
  ASSERT_TRUE(node.remove(ctl));
  ex.run_until(kernel::Time{1000ms});
  EXPECT_EQ(sink->stats().timeouts, 2u);
  EXPECT_EQ(motors->output(), kSafe);
}

// While commands flow, a sink tick that finds the deadline ahead skips the ticks before it; the
// instant the wheels stop is the one a tick every period gives (the test above: 440 ms).
TEST(ActuatorWatchdog, WhileCommandsFlowTheSinkTicksOnceACommandNotEveryPeriod) {
  kernel::VirtualTimeExecutor ex;
  os::Node node(ex, {"bot"});
  auto motors = std::make_shared<RecordingMotors>(ex);
  ActuatorSinkTask::Options o;
  o.timeout = 45ms;
  auto sink = *node.create("wheels", std::make_unique<ActuatorSinkTask>(motors, o), {.period = 10ms});
  auto ctl = *node.create("ctl", std::make_unique<Driver>(kDrive), {.priority = 2, .period = 30ms});
  ASSERT_TRUE(node.hook(ctl, sink));
  ex.run_until(kernel::Time{400ms});
  // In (400, 700] ms: the controller's 10 ticks (420 to 690) and 10 of the sink's, each the first
  // of its 10 ms grid at least 45 ms past the command before it (410, 440, ..., 680), not 30.
  EXPECT_EQ(ex.run_until(kernel::Time{700ms}), 20u);
  EXPECT_EQ(motors->applied.size(), 23u);  // every command applied: 30 ms to 690 ms
  EXPECT_EQ(motors->output(), kDrive);
}

// A shorter timeout set while ticks are skipped for the old one counts from the change.
TEST(ActuatorWatchdog, AShorterTimeoutIsNotHeldBackByTicksSkippedForTheOldOne) {
  kernel::VirtualTimeExecutor ex;
  auto motors = std::make_shared<RecordingMotors>(ex);
  MotorTypes types(motors);
  ASSERT_TRUE(types.registered) << types.registered.error();
  os::Node node(ex, {.name = "bot", .types = &types.registry});
  auto params = os::parse_param_assignments("device=motors timeout=500ms");
  ASSERT_TRUE(params);
  auto sink = node.create("actuator_sink", "wheels", *params, os::TaskOptions{.period = 10ms});
  ASSERT_TRUE(sink) << sink.error();
  auto ctl = *node.create("ctl", std::make_unique<Driver>(kDrive), {.priority = 2, .period = 30ms});
  ASSERT_TRUE(node.hook(ctl, *sink));
  ex.run_until(kernel::Time{105ms});  // the sink's tick at 100 ms skipped those up to 590 (90 + 500)
  ASSERT_TRUE(node.suspend(ctl));
  ASSERT_TRUE(node.set_parameter(*sink, "timeout", "40ms"));
  ex.run_until(kernel::Time{300ms});
  ASSERT_FALSE(motors->applied.empty());
  EXPECT_EQ(motors->applied.back().values, kSafe);
  // The change, applied at 105 ms, restarts the ticks (115, 125, ...): the first at least 40 ms on.
  EXPECT_EQ(motors->applied.back().time, kernel::Time{145ms});
}

TEST(ActuatorWatchdog, OffByDefaultAndRefusedCommandsDoNotFeedIt) {
  kernel::VirtualTimeExecutor ex;
  os::Node node(ex, {"bot"});
  auto motors = std::make_shared<RecordingMotors>(ex);
  auto quiet = std::make_unique<ActuatorSinkTask>(motors);
  ActuatorSinkTask* off = quiet.get();
  ASSERT_TRUE(node.create("off", std::move(quiet), {.period = 10ms}));
  ex.run_until(kernel::Time{1s});
  EXPECT_EQ(off->stats().timeouts, 0u);
  EXPECT_TRUE(motors->applied.empty());

  // A controller that only sends a wrong number of values: the sink refuses each, and the
  // watchdog, counting from the sink's start, still stops the wheels.
  auto motors2 = std::make_shared<RecordingMotors>(ex);
  ActuatorSinkTask::Options o;
  o.timeout = 45ms;
  auto t = std::make_unique<ActuatorSinkTask>(motors2, o);
  ActuatorSinkTask* sink = t.get();
  auto sink_id = *node.create("wheels", std::move(t), {.period = 10ms});
  auto bad = *node.create("bad", std::make_unique<Driver>(std::vector<float>{1, 2}), {.period = 30ms});
  ASSERT_TRUE(node.hook(bad, sink_id));
  const kernel::Time started = ex.now();
  ex.run_for(200ms);
  EXPECT_GT(sink->stats().failed, 4u);
  EXPECT_EQ(sink->stats().timeouts, 1u);
  ASSERT_EQ(motors2->applied.size(), 1u);
  EXPECT_EQ(motors2->applied[0].values, kSafe);
  EXPECT_EQ(motors2->applied[0].time - started, 50ms);
}

TEST(ActuatorWatchdog, TaskTypeTakesTheTimeoutAsADurationAndTicksOnlyWithAWatchdog) {
  kernel::VirtualTimeExecutor ex;
  auto motors = std::make_shared<RecordingMotors>(ex);
  MotorTypes types(motors);
  ASSERT_TRUE(types.registered) << types.registered.error();
  const os::TaskType* type = types.registry.find("actuator_sink");
  ASSERT_NE(type, nullptr);
  ASSERT_NE(type->param("timeout"), nullptr);
  EXPECT_EQ(type->param("timeout")->type, os::ParamType::kDuration);
  EXPECT_EQ(std::get<kernel::Duration>(type->param("timeout")->default_value), kernel::Duration{0});
  EXPECT_EQ(type->defaults.period, kernel::Duration{0});  // no ticks for a sink without a watchdog
  EXPECT_EQ(type->defaults.priority, -1);                 // its ticks after a command of the same instant

  os::Node node(ex, {.name = "bot", .types = &types.registry});
  auto params = os::parse_param_assignments("device=motors timeout=45ms");
  ASSERT_TRUE(params);
  auto sink = node.create("actuator_sink", "wheels", *params);
  ASSERT_TRUE(sink) << sink.error();
  auto ctl = *node.create("ctl", std::make_unique<Driver>(kDrive), {.period = 30ms});
  ASSERT_TRUE(node.hook(ctl, *sink));
  ex.run_until(kernel::Time{300ms});
  EXPECT_EQ(node.info(*sink)->period, kernel::Duration{15ms});  // given itself a third of the timeout
  EXPECT_EQ(motors->output(), kDrive);
  ASSERT_TRUE(node.suspend(ctl));  // last command at 300 ms
  ex.run_until(kernel::Time{400ms});
  EXPECT_EQ(motors->output(), kSafe);
  EXPECT_LE(motors->applied.back().time, kernel::Time{360ms});

  // Switched off at runtime: a silence no longer stops anything.
  ASSERT_TRUE(node.set_parameter(*sink, "timeout", "0s"));
  ASSERT_TRUE(node.resume(ctl));
  ex.run_until(kernel::Time{500ms});
  ASSERT_TRUE(node.suspend(ctl));
  const std::size_t applied = motors->applied.size();
  ex.run_until(kernel::Time{900ms});
  EXPECT_EQ(motors->applied.size(), applied);
  EXPECT_EQ(motors->output(), kDrive);

  auto negative = os::parse_param_assignments("device=motors timeout=-1ms");
  ASSERT_TRUE(negative);
  EXPECT_FALSE(node.create("actuator_sink", "w2", *negative));
}

}  // namespace
}  // namespace symb::robot
