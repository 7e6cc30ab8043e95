// The 3D world's devices and runner: task graphs on the modules' nodes drive a hinge to a target
// and read it back, drive a module forward, see a neighbour by IR and dock two modules through
// the connector ioctls (both nodes' logs record it; a refusal answers with the world's reason);
// the same seed gives a bit-identical run; a diverging world stops the runner with its error. The
// figures written beside the bounds were measured once with this file (release build).
#include <chrono>
#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "symb/kernel/thread_executor.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/robot/actuator.hpp"
#include "symb/robot/ports.hpp"
#include "symb/robot/robot_task_types.hpp"
#include "symb/robot/sensor.hpp"
#include "symb/sim/mujoco/mujoco_runner.hpp"
#include "symb/sim/robot_system.hpp"

#include "support/eventually.hpp"
#include "support/measured.hpp"

namespace symb::sim::mujoco {
namespace {

using namespace std::chrono_literals;
constexpr kernel::Duration kDevPeriod = 30ms;

// Sends the same numbers on the data port at every tick (a controller that holds one command).
class DevSource final : public os::Task {
 public:
  explicit DevSource(std::vector<float> values) : values_(std::move(values)) {}

 protected:
  void on_tick() override { send(robot::kDataPort, values_); }

 private:
  std::vector<float> values_;
};

// Sends a new hinge target drawn from its own random stream every 5 ticks (0.15 s).
class DevWaver final : public os::Task {
 protected:
  void on_tick() override {
    if (ticks_++ % 5 == 0) target_ = static_cast<float>(random().uniform(-0.8, 0.8));
    send(robot::kDataPort, {target_});
  }

 private:
  std::uint64_t ticks_ = 0;
  float target_ = 0;
};

// Keeps every message's numbers and time.
class DevRecorder final : public os::Task {
 public:
  struct Seen {
    kernel::Time time{0};
    std::vector<float> values;
  };
  std::vector<Seen> seen() const {
    std::lock_guard lock(mu_);
    return seen_;
  }

 protected:
  void on_message(const os::Message& m) override {
    std::lock_guard lock(mu_);
    seen_.push_back({m.time, std::vector<float>(m.numbers().begin(), m.numbers().end())});
  }

 private:
  mutable std::mutex mu_;
  std::vector<Seen> seen_;
};

// At its first tick at or after `at`, sends the ioctls to the device, in order, once, and keeps
// the answers ("ok: <text>" or "error: <text>").
class DevIoctlCaller final : public os::Task {
 public:
  DevIoctlCaller(std::shared_ptr<io::Device> device, std::vector<std::string> commands, kernel::Time at)
      : device_(std::move(device)), commands_(std::move(commands)), at_(at) {}
  std::vector<std::string> answers() const {
    std::lock_guard lock(mu_);
    return answers_;
  }

 protected:
  void on_tick() override {
    if (done_ || now() < at_) return;
    done_ = true;
    for (const std::string& command : commands_) {
      const auto answer = device_->ioctl(command);
      std::lock_guard lock(mu_);
      answers_.push_back(answer ? "ok: " + *answer : "error: " + answer.error());
    }
  }

 private:
  std::shared_ptr<io::Device> device_;
  std::vector<std::string> commands_;
  kernel::Time at_;
  bool done_ = false;
  mutable std::mutex mu_;
  std::vector<std::string> answers_;
};

// A world, its runner and one node per module (seeded per module from `seed`), all on one
// executor. The nodes hear of their modules' docking changes.
template <class Executor = kernel::VirtualTimeExecutor>
struct DeviceRig {
  Executor ex;
  MujocoWorld world;
  std::unique_ptr<MujocoRunner> runner;
  std::vector<std::unique_ptr<os::Node>> nodes;

  static MujocoWorld make(std::vector<ModuleSpec> specs) {
    auto made = MujocoWorld::make(std::move(specs));
    EXPECT_TRUE(made.ok()) << made.error();
    return std::move(made).value();
  }

  explicit DeviceRig(std::vector<ModuleSpec> specs, std::uint64_t seed = 1) : world(make(std::move(specs))) {
    runner = std::make_unique<MujocoRunner>(ex, world, PeriodicRunner::Options{.period = kDevPeriod});
    for (std::size_t m = 0; m < world.module_count(); ++m) {
      nodes.push_back(std::make_unique<os::Node>(ex, os::NodeConfig{world.module(m).name, robot_node_seed(seed, m)}));
      runner->set_node(m, nodes.back().get());
    }
  }
  ~DeviceRig() {
    runner.reset();  // stops it and detaches the nodes
    nodes.clear();
  }

  os::Node& node(std::size_t m) { return *nodes[m]; }
  template <class T>
  T* add(std::size_t m, const std::string& name, std::unique_ptr<T> task, kernel::Duration period = {}) {
    T* raw = task.get();
    os::TaskOptions options;
    options.period = period;
    const auto id = node(m).create(name, std::move(task), options);
    EXPECT_TRUE(id.ok()) << id.error();
    return raw;
  }
  void hook(std::size_t m, const std::string& from, const std::string& to) {
    const auto r = node(m).hook(*node(m).find(from), *node(m).find(to));
    EXPECT_TRUE(r.ok()) << r.error();
  }
  // Every log line of module m's node, as "source: text".
  std::vector<std::string> log_lines(std::size_t m) {
    std::vector<std::string> lines;
    for (const auto& e : node(m).log().since(0)) lines.push_back(e.source + ": " + e.text);
    return lines;
  }
};

bool dev_has_line(const std::vector<std::string>& lines, const std::string& part) {
  for (const auto& l : lines)
    if (l.find(part) != std::string::npos) return true;
  return false;
}

std::string dev_joined(const std::vector<std::string>& lines) {
  std::string all;
  for (const auto& l : lines) all += l + "\n";
  return all;
}

// Two standard modules front to front, their front connectors `gap` metres apart.
std::vector<ModuleSpec> dev_face_to_face(double gap) {
  const ModuleKind kind = standard_kind();
  const double length = kind.body.size[0];
  return {{"a", kind, {0, 0, 0}}, {"b", kind, {length + gap, 0, std::numbers::pi}}};
}

TEST(MujocoDevices, HingeTaskGraphReachesItsTargetAndReadsItBack) {
  // source -> hinge (actuator sink); hinge_state (sensor task) -> recorder, on module a's node.
  constexpr float kTarget = 0.5f;
  DeviceRig rig({{"a", standard_kind(), {0, 0, 0}}});
  rig.add(0, "source", std::make_unique<DevSource>(std::vector<float>{kTarget}), kDevPeriod);
  rig.add(0, "hinge", std::make_unique<robot::ActuatorSinkTask>(rig.runner->hinge(0)));
  rig.add(0, "hinge_state", std::make_unique<robot::SensorTask>(rig.runner->hinge_sensor(0)));
  auto* recorder = rig.add(0, "recorder", std::make_unique<DevRecorder>());
  rig.hook(0, "source", "hinge");
  rig.hook(0, "hinge_state", "recorder");
  std::vector<MujocoStepRecord> records;
  rig.runner->add_observer([&](const MujocoStepRecord& r) { records.push_back(r); });
  ASSERT_TRUE(rig.runner->start());
  rig.ex.run_for(1500ms);

  // 50 ticks of 15 steps each: the world moved 1.5 s.
  ASSERT_EQ(records.size(), 50U);
  EXPECT_EQ(rig.runner->ticks(), 50U);
  EXPECT_EQ(records.back().step, 750U);
  EXPECT_EQ(rig.world.steps(), 750U);
  const auto seen = recorder->seen();
  ASSERT_EQ(seen.size(), records.size());
  for (std::size_t i = 0; i < seen.size(); ++i) {
    // Every reading reached the recorder at the tick's instant, with the world's values.
    ASSERT_EQ(seen[i].time, records[i].time);
    ASSERT_EQ(seen[i].values.size(), 2U);
    EXPECT_EQ(seen[i].values[0], static_cast<float>(records[i].modules[0].hinge_angle));
    EXPECT_EQ(seen[i].values[1], static_cast<float>(records[i].modules[0].hinge_speed));
  }
  // The first tick ran before any command (the target was 0); from the second on, the source's.
  EXPECT_EQ(records[0].modules[0].hinge_target, 0.0);
  EXPECT_EQ(records[1].modules[0].hinge_target, static_cast<double>(kTarget));
  // Read back through the sensor: within 0.01 rad of the target, at rest. Measured: 0.4961 rad
  // (the servo ends 0.0039 rad short: it lifts the module).
  EXPECT_NEAR(seen.back().values[0], kTarget, 0.01);
  EXPECT_TRUE(symb::testing::near_measured(seen.back().values[0], 0.4961, 0.002));
  EXPECT_LT(std::abs(seen.back().values[1]), 0.01);
  // The source's 50th command came at 1.5 s, just after the runner's last tick (higher priority).
  EXPECT_EQ(rig.runner->hinge(0)->command().sequence, 50U);
}

TEST(MujocoDevices, WheelsDriveAModuleForwardAMeasuredDistance) {
  // Half the motor range (250 of 500 units) is half the kind's top rim speed: 0.075 m/s.
  DeviceRig rig({{"a", standard_kind(), {0, 0, 0}}});
  rig.add(0, "source", std::make_unique<DevSource>(std::vector<float>{250, 250}), kDevPeriod);
  rig.add(0, "wheels", std::make_unique<robot::ActuatorSinkTask>(rig.runner->wheels(0)));
  rig.hook(0, "source", "wheels");
  std::vector<MujocoStepRecord> records;
  rig.runner->add_observer([&](const MujocoStepRecord& r) { records.push_back(r); });
  ASSERT_TRUE(rig.runner->start());
  rig.ex.run_for(2s);
  ASSERT_EQ(records.size(), 66U);
  EXPECT_DOUBLE_EQ(records.back().modules[0].wheels[0], 0.075);
  EXPECT_DOUBLE_EQ(records.back().modules[0].wheels[1], 0.075);
  const Pose3 start = records.front().modules[0].pose, end = records.back().modules[0].pose;
  const double forward = end.position[0] - start.position[0];
  const double sideways = end.position[1] - start.position[1];
  // The steady speed over the last second (33 ticks): the wheels' velocity servo (a P law on the
  // rim speed) droops a little under the casters' friction. Measured: 73.3 mm/s of the 75
  // commanded (98%; mujoco_sensors_test.cpp holds the servo to 97%).
  const double steady = (end.position[0] - records[records.size() - 34].modules[0].pose.position[0]) / (33 * 0.030);
  EXPECT_TRUE(symb::testing::near_measured(steady, 0.0733, 0.002));
  EXPECT_LT(steady, 0.075);
  // 65 ticks (1.95 s). Measured: 142.4 mm forward, 0.000 mm sideways, heading unchanged.
  EXPECT_TRUE(symb::testing::near_measured(forward, 0.1424, 0.002));
  EXPECT_LT(std::abs(sideways), 0.001);
  EXPECT_LT(std::abs(end.yaw()), 0.01);
  EXPECT_EQ(rig.runner->wheels(0)->command().sequence, 66U);
}

TEST(MujocoDevices, IrThroughTheDeviceSeesAModuleInFront) {
  const ModuleKind kind = standard_kind();
  const double length = kind.body.size[0];
  DeviceRig rig({{"a", kind, {0, 0, 0}}, {"b", kind, {length + 0.05, 0, 0}}});
  rig.add(0, "ir", std::make_unique<robot::SensorTask>(rig.runner->ir_sensor(0)));
  auto* a_seen = rig.add(0, "recorder", std::make_unique<DevRecorder>());
  rig.hook(0, "ir", "recorder");
  rig.add(1, "ir", std::make_unique<robot::SensorTask>(rig.runner->ir_sensor(1)));
  auto* b_seen = rig.add(1, "recorder", std::make_unique<DevRecorder>());
  rig.hook(1, "ir", "recorder");
  ASSERT_TRUE(rig.runner->start());
  rig.ex.run_for(300ms);
  const auto a = a_seen->seen(), b = b_seen->seen();
  ASSERT_EQ(a.size(), 10U);
  ASSERT_EQ(b.size(), 10U);
  // Channels front, back, left, right. 50 mm of the front sensor's 150 mm range: 1 - 50/150.
  // Measured: 0.6661 (50.08 mm, the settled bodies lean a little).
  const double expected = 1 - 0.05 / kind.ir.front().range;
  EXPECT_NEAR(a.back().values[0], expected, 0.01);
  EXPECT_TRUE(symb::testing::near_measured(a.back().values[0], 0.6661, 0.002));
  for (std::size_t f : {1U, 2U, 3U}) EXPECT_EQ(a.back().values[f], 0.0f) << face_name(kFaces[f]);
  EXPECT_NEAR(b.back().values[1], expected, 0.01);  // b sees a behind it
  EXPECT_EQ(b.back().values[0], 0.0f);
  // The shell's view of the device agrees: the newest sample, time then the four channels.
  const auto latest = rig.runner->ir_sensor(0)->ioctl("latest");
  ASSERT_TRUE(latest.ok()) << latest.error();
  EXPECT_EQ(latest->substr(0, latest->find(' ')), std::to_string(kernel::Time{300ms}.count()));
}

TEST(MujocoDevices, ATaskLatchesTwoModulesThroughTheConnectorIoctlsAndBothLogsRecordIt) {
  DeviceRig rig(dev_face_to_face(0.005));
  auto front_a = rig.runner->connector(0, "front");
  auto front_b = rig.runner->connector(1, "front");
  ASSERT_TRUE(front_a && front_b);
  EXPECT_EQ(front_a->name(), "connector_front");
  EXPECT_EQ(rig.runner->connector(0, "top"), nullptr);
  auto* latcher = rig.add(0, "latcher",
                          std::make_unique<DevIoctlCaller>(front_a, std::vector<std::string>{"state", "latch", "state"},
                                                           kernel::Time{300ms}),
                          kDevPeriod);
  // b's node watches its own front connector through a sensor task.
  rig.add(1, "connector", std::make_unique<robot::SensorTask>(front_b));
  auto* b_seen = rig.add(1, "recorder", std::make_unique<DevRecorder>());
  rig.hook(1, "connector", "recorder");
  ASSERT_TRUE(rig.runner->start());
  rig.ex.run_for(600ms);

  const auto answers = latcher->answers();
  ASSERT_EQ(answers.size(), 3U);
  EXPECT_EQ(answers[0], "ok: aligned, open");
  EXPECT_EQ(answers[1], "ok: docked to b.front, open");
  EXPECT_EQ(answers[2], "ok: docked to b.front, open");
  EXPECT_EQ(front_b->ioctl("state").value(), "docked to a.front, open");
  const auto a_log = rig.log_lines(0), b_log = rig.log_lines(1);
  EXPECT_TRUE(dev_has_line(a_log, "connector_front: latched front to b.front")) << dev_joined(a_log);
  EXPECT_TRUE(dev_has_line(b_log, "connector_front: latched front to a.front (latched by a)")) << dev_joined(b_log);
  // b's connector readings: aligned before the latch (state 1, open, no peer), docked to module 0 after.
  const auto seen = b_seen->seen();
  ASSERT_EQ(seen.size(), 20U);
  // (The first three channels; the beacon's follow, tests/sim/self_assembly_test.cpp.)
  const auto first3 = [](const std::vector<float>& v) { return std::vector<float>(v.begin(), v.begin() + 3); };
  ASSERT_EQ(seen.front().values.size(), 6U);
  EXPECT_EQ(first3(seen.front().values), (std::vector<float>{1, 1, -1}));
  EXPECT_EQ(first3(seen.back().values), (std::vector<float>{2, 1, 0}));

  // Unlatching from b's side is logged on both nodes too.
  const auto parted = front_b->ioctl("unlatch");
  ASSERT_TRUE(parted.ok()) << parted.error();
  EXPECT_TRUE(dev_has_line(rig.log_lines(0), "unlatched front to b.front (unlatched by b)"));
  EXPECT_TRUE(dev_has_line(rig.log_lines(1), "connector_front: unlatched front to a.front"));
}

TEST(MujocoDevices, ARefusedLatchAnswersWithTheWorldsReason) {
  DeviceRig rig(dev_face_to_face(0.030));
  auto front_a = rig.runner->connector(0, "front");
  auto front_b = rig.runner->connector(1, "front");
  auto* latcher = rig.add(0, "latcher",
                          std::make_unique<DevIoctlCaller>(front_a, std::vector<std::string>{"latch"}, kernel::Time{0}),
                          kDevPeriod);
  ASSERT_TRUE(rig.runner->start());
  rig.ex.run_for(100ms);
  const auto answers = latcher->answers();
  ASSERT_EQ(answers.size(), 1U);
  EXPECT_EQ(answers[0].rfind("error: latch a.front refused: position: b.front is ", 0), 0U) << answers[0];
  EXPECT_NE(answers[0].find("beyond the tolerance of 15"), std::string::npos) << answers[0];
  EXPECT_TRUE(dev_has_line(rig.log_lines(0), "connector_front: refused front: position: b.front is "))
      << dev_joined(rig.log_lines(0));
  EXPECT_FALSE(dev_has_line(rig.log_lines(1), "refused"));  // only the one who asked hears of it

  // A closed partner: the refusal names it; closing and opening are logged on the connector's node.
  rig.runner->stop();
  ASSERT_TRUE(rig.world.place(1, {standard_kind().body.size[0] + 0.005, 0, std::numbers::pi}).ok());
  ASSERT_TRUE(rig.world.step(100).ok());
  EXPECT_EQ(front_b->ioctl("close").value(), "aligned, closed");
  const auto refused = front_a->ioctl("latch");
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().find("the nearest connector, b.front, is closed"), std::string::npos) << refused.error();
  EXPECT_EQ(front_b->ioctl("open").value(), "aligned, open");
  EXPECT_TRUE(dev_has_line(rig.log_lines(1), "connector_front: closed"));
  EXPECT_TRUE(dev_has_line(rig.log_lines(1), "connector_front: opened"));
  EXPECT_EQ(front_a->ioctl("latch").value(), "docked to b.front, open");
  EXPECT_FALSE(front_a->ioctl("latch").ok());  // already docked
  EXPECT_NE(front_a->ioctl("wobble").error().find("wobble"), std::string::npos);
}

TEST(MujocoDevices, APeriodOfNoWholeStepsNeverDrifts) {
  // 25 ms is 12.5 steps: the ticks take 12 and 13 in turn, and the world keeps the node's time.
  kernel::VirtualTimeExecutor ex;
  auto made = MujocoWorld::make({{"a", standard_kind(), {0, 0, 0}}});
  ASSERT_TRUE(made.ok()) << made.error();
  MujocoWorld world = std::move(made).value();
  MujocoRunner runner(ex, world, PeriodicRunner::Options{.period = 25ms});
  std::vector<std::uint64_t> steps;
  runner.add_observer([&](const MujocoStepRecord& r) {
    steps.push_back(r.step);
    EXPECT_LE(std::abs(static_cast<double>(r.step) * kTimestep - std::chrono::duration<double>(r.time).count()),
              kTimestep);
  });
  ASSERT_TRUE(runner.start());
  ex.run_for(1s);
  ASSERT_EQ(steps.size(), 40U);
  EXPECT_EQ(steps[0], 12U);
  EXPECT_EQ(steps[1], 25U);
  EXPECT_EQ(steps.back(), 500U);
  EXPECT_EQ(world.steps(), 500U);
}

TEST(MujocoDevices, DockingThroughTheWorldIsLoggedAtTheNextTick) {
  // A shell or a scenario docks through with_world, not through a device: the runner's next tick
  // writes it to both nodes' logs all the same.
  DeviceRig rig(dev_face_to_face(0.005));
  ASSERT_TRUE(rig.runner->start());
  rig.ex.run_for(150ms);
  bool latched = false;
  ASSERT_TRUE(
      rig.runner->with_world([&](MujocoWorld& w) { latched = w.latch(1, *w.find_connector(1, "front")).ok(); }));
  ASSERT_TRUE(latched);
  EXPECT_FALSE(dev_has_line(rig.log_lines(0), "latched"));
  rig.ex.run_for(30ms);
  EXPECT_TRUE(dev_has_line(rig.log_lines(0), "connector_front: latched front to b.front (latched by b)"))
      << dev_joined(rig.log_lines(0));
  EXPECT_TRUE(dev_has_line(rig.log_lines(1), "connector_front: latched front to a.front"));
}

TEST(MujocoDevices, AConnectorThatOutlivesItsRunnerSaysTheWorldIsGone) {
  DeviceRig rig(dev_face_to_face(0.005));
  auto front = rig.runner->connector(0, "front");
  EXPECT_EQ(front->ioctl("state").value(), "aligned, open");
  rig.runner.reset();
  const auto answer = front->ioctl("latch");
  ASSERT_FALSE(answer.ok());
  EXPECT_NE(answer.error().find("the world is gone"), std::string::npos) << answer.error();
  EXPECT_FALSE(front->ioctl("open").ok());
}

TEST(MujocoDevices, TaskTypesByNameFindTheModulesDevices) {
  // The robot layer's `sensor` and `actuator_sink` types, created by name as a shell or a scenario
  // does, bind to the module's devices through the runner's lookups.
  DeviceRig rig(dev_face_to_face(0.005));
  os::TaskTypeRegistry types;
  ASSERT_TRUE(robot::register_robot_task_types(types, rig.runner->device_lookups(0)).ok());
  os::Node node(rig.ex, os::NodeConfig{"a_by_name", 3, 64, &types});
  auto create = [&](std::string_view type, const std::string& device) {
    const std::vector<os::ParamAssignment> params{{"device", device, 1}};
    return node.create(type, device, params);
  };
  ASSERT_TRUE(create("actuator_sink", "hinge").ok());
  ASSERT_TRUE(create("actuator_sink", "wheels").ok());
  ASSERT_TRUE(create("sensor", "hinge_state").ok());
  ASSERT_TRUE(create("sensor", "connector_front").ok());
  const auto missing = create("sensor", "connector_top");
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().find("connector_top"), std::string::npos) << missing.error();
  EXPECT_FALSE(create("actuator_sink", "ir").ok());  // a sensor is no actuator
  ASSERT_TRUE(rig.runner->start());
  rig.ex.run_for(90ms);
  EXPECT_TRUE(rig.runner->hinge_sensor(0)->has_listener());
  EXPECT_TRUE(rig.runner->connector(0, "front")->has_listener());
  EXPECT_TRUE(rig.runner->hinge(0)->is_open());  // opened by its sink at start
  ASSERT_TRUE(rig.runner->connector(0, "front")->latest().has_value());
  node.clear();
}

// A fixed task graph on two modules: a waves its hinge to random targets from its node's stream
// and drives; b drives in a curve. Returns every tick's poses and hinge angles.
std::vector<double> dev_seeded_run(std::uint64_t seed) {
  const ModuleKind kind = standard_kind();
  DeviceRig rig({{"a", kind, {0, 0, 0}}, {"b", kind, {0, 0.3, 0.5}}}, seed);
  rig.add(0, "waver", std::make_unique<DevWaver>(), kDevPeriod);
  rig.add(0, "hinge", std::make_unique<robot::ActuatorSinkTask>(rig.runner->hinge(0)));
  rig.hook(0, "waver", "hinge");
  rig.add(0, "drive", std::make_unique<DevSource>(std::vector<float>{300, 300}), kDevPeriod);
  rig.add(0, "wheels", std::make_unique<robot::ActuatorSinkTask>(rig.runner->wheels(0)));
  rig.hook(0, "drive", "wheels");
  rig.add(1, "drive", std::make_unique<DevSource>(std::vector<float>{400, 150}), kDevPeriod);
  rig.add(1, "wheels", std::make_unique<robot::ActuatorSinkTask>(rig.runner->wheels(1)));
  rig.hook(1, "drive", "wheels");
  std::vector<double> trace;
  rig.runner->add_observer([&](const MujocoStepRecord& r) {
    for (const ModuleStep& m : r.modules) {
      trace.insert(trace.end(), m.pose.position.begin(), m.pose.position.end());
      trace.insert(trace.end(), m.pose.quaternion.begin(), m.pose.quaternion.end());
      trace.push_back(m.hinge_angle);
    }
  });
  EXPECT_TRUE(rig.runner->start());
  rig.ex.run_for(3s);
  return trace;
}

TEST(MujocoDevices, SameSeedGivesABitIdenticalRunUnderVirtualTime) {
  const auto first = dev_seeded_run(7), second = dev_seeded_run(7), other = dev_seeded_run(8);
  ASSERT_EQ(first.size(), 100U * 2 * 8);
  ASSERT_EQ(first.size(), second.size());
  EXPECT_EQ(std::memcmp(first.data(), second.data(), first.size() * sizeof(double)), 0);
  // Another seed draws other hinge targets, and the run differs.
  ASSERT_EQ(first.size(), other.size());
  EXPECT_NE(std::memcmp(first.data(), other.data(), first.size() * sizeof(double)), 0);
}

TEST(MujocoDevices, ADivergingWorldStopsTheRunnerWithTheError) {
  // A hinge servo 250 times too stiff for the 2 ms step, with no damping: Euler blows up.
  ModuleKind kind = standard_kind();
  kind.hinge.gain = 1000;
  kind.hinge.damping = 0;
  DeviceRig rig({{"a", kind, {0, 0, 0}}});
  rig.add(0, "source", std::make_unique<DevSource>(std::vector<float>{0.3f}), kDevPeriod);
  rig.add(0, "hinge", std::make_unique<robot::ActuatorSinkTask>(rig.runner->hinge(0)));
  rig.hook(0, "source", "hinge");
  rig.add(0, "hinge_state", std::make_unique<robot::SensorTask>(rig.runner->hinge_sensor(0)));
  ASSERT_TRUE(rig.runner->start());
  rig.ex.run_for(1s);  // returns: the tasks go on without the world
  EXPECT_FALSE(rig.runner->running());
  const std::string error = rig.runner->error();
  EXPECT_NE(error.find("world runner 'world' stopped: world step failed: step "), std::string::npos) << error;
  EXPECT_NE(error.find("diverged"), std::string::npos) << error;
  EXPECT_TRUE(rig.world.failed());
  // Measured: the first tick fails, at step 12 of its 15 (the servo cannot even hold the module
  // straight while it settles on its wheels).
  EXPECT_EQ(rig.runner->ticks(), 0U);
  EXPECT_LT(rig.world.steps(), 15U);
  EXPECT_TRUE(dev_has_line(rig.log_lines(0), "world: " + error)) << dev_joined(rig.log_lines(0));
  EXPECT_GT(rig.node(0).info(*rig.node(0).find("source"))->sent, 30U);  // the node ran on
  // Starting again reports the failed world at once.
  ASSERT_TRUE(rig.runner->start());
  rig.ex.run_for(100ms);
  EXPECT_FALSE(rig.runner->running());
  EXPECT_NE(rig.runner->error().find("the world has failed and does not step"), std::string::npos)
      << rig.runner->error();
}

TEST(MujocoDevices, ConnectorIoctlsFromAThreadWhileTheRunnerStepsOnAnother) {
  // Under the thread executor: the runner ticks on its own thread, a task latches on another; the
  // world's lock serialises them.
  DeviceRig<kernel::ThreadExecutor> rig(dev_face_to_face(0.005));
  auto front_a = rig.runner->connector(0, "front");
  auto* latcher =
      rig.add(0, "latcher",
              std::make_unique<DevIoctlCaller>(front_a, std::vector<std::string>{"latch", "unlatch", "latch"},
                                               rig.ex.clock().now() + 100ms),
              10ms);
  ASSERT_TRUE(rig.runner->start());
  // Waited for, not slept for: on a busy box either thread may be kept off its core for seconds.
  // The partner hears of the unlatch on the runner's next tick.
  symb::testing::eventually([&] { return latcher->answers().size() >= 3; });
  symb::testing::eventually([&] {
    return rig.runner->ticks() > 3 && dev_has_line(rig.log_lines(1), "unlatched front to a.front (unlatched by a)");
  });
  rig.runner->stop();
  const auto answers = latcher->answers();
  ASSERT_EQ(answers.size(), 3U);
  EXPECT_EQ(answers[0], "ok: docked to b.front, open");
  EXPECT_EQ(answers[2], "ok: docked to b.front, open");
  EXPECT_TRUE(rig.runner->error().empty()) << rig.runner->error();
  EXPECT_GT(rig.runner->ticks(), 3U);
  bool docked = false;
  EXPECT_TRUE(rig.runner->with_world(
      [&](MujocoWorld& w) { docked = w.docked_to(0, *w.find_connector(0, "front")).has_value(); }));
  EXPECT_TRUE(docked);
  EXPECT_TRUE(dev_has_line(rig.log_lines(1), "unlatched front to a.front (unlatched by a)"));
}

}  // namespace
}  // namespace symb::sim::mujoco
