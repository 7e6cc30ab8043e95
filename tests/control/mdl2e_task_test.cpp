// The MDL2e controller task in a node under virtual time: a scripted sensor task feeds IR vectors
// to the controller, whose wheel commands a recording task keeps with their times. Checks the
// reaction at the instant of a new vector, the fixed rate without new data, what happens when a
// tick and a vector meet at one instant, task actions, bad input, plan end, suspend/resume,
// replacing the controller at runtime, the task type and the shipped obstacle-avoidance program.
#include "symb/control/mdl2e/mdl2e_task.hpp"

#include <atomic>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>

#include <gtest/gtest.h>

#include "symb/control/control_task_types.hpp"
#include "symb/control/mdl2e/compiler.hpp"
#include "symb/kernel/thread_executor.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"

#include "support/virtual_time.hpp"

namespace symb::control {
namespace {

using namespace std::chrono_literals;
using kernel::Time;
using IR = std::vector<float>;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

using test_support::ms;

// Sends the IR vector scripted for an instant at its tick of that instant (and nothing else).
// A vector scripted with `queued_to` is posted into that task's queue instead, as from outside
// any task: the controller, which takes what is sent to it at once, finds it waiting.
class Mdl2eSensor : public os::Task {
 public:
  void script(Time t, IR ir, os::TaskId queued_to = {}) { script_[t] = {std::move(ir), queued_to}; }

 protected:
  void on_tick() override {
    auto it = script_.find(now());
    if (it == script_.end()) return;
    const auto& [ir, queued_to] = it->second;
    if (!queued_to.valid()) return send(kSensorPort, ir);
    os::Message m;
    m.port = kSensorPort;
    m.time = now();
    m.payload = os::Payload(std::span<const float>(ir));
    ASSERT_TRUE(node().post(queued_to, m));
  }

 private:
  std::map<Time, std::pair<IR, os::TaskId>> script_;
};

// Keeps every wheel command with its time.
class Mdl2eRecorder : public os::Task {
 public:
  struct Command {
    Time time;
    float left, right;
  };
  std::vector<Command> commands() const {
    std::lock_guard lock(mu_);
    return commands_;
  }
  std::vector<Command> at(Time t) const {
    std::vector<Command> out;
    for (const auto& c : commands())
      if (c.time == t) out.push_back(c);
    return out;
  }
  Command last() const {
    std::lock_guard lock(mu_);
    return commands_.empty() ? Command{Time{-1}, kNaN, kNaN} : commands_.back();
  }
  std::size_t size() const {
    std::lock_guard lock(mu_);
    return commands_.size();
  }

 protected:
  void on_message(const os::Message& m) override {
    ASSERT_EQ(m.numbers().size(), 2u);
    std::lock_guard lock(mu_);
    commands_.push_back({m.time, m.numbers()[0], m.numbers()[1]});
  }

 private:
  mutable std::mutex mu_;
  std::vector<Command> commands_;
};

// A task that does nothing: a target for task actions.
class Idle : public os::Task {};

std::shared_ptr<const mdl2e::Program> compile(std::string_view source) {
  auto p = mdl2e::compile_source(source);
  EXPECT_TRUE(p.ok()) << (p.ok() ? std::string() : p.error());
  return std::make_shared<const mdl2e::Program>(p.ok() ? std::move(p).value() : mdl2e::Program{});
}

// Drive forward; turn left while something is in front; stop for good when bumped.
constexpr std::string_view kAvoid = R"(
sensor ir[7]
interrupt front = ir[2] > 2000
interrupt bumped = external
plan p {
  behaviour cruise loop until bumped {
    atom forward(100) until front
    atom turn(80) until not front
  }
  atom backward(40) for 100ms
}
)";

const IR kClearIr{0, 0, 0, 0, 0, 0, 0};
const IR kWall{0, 0, 3000, 0, 0, 0, 0};

// sensor -> controller -> recorder on one node, each made in code.
struct Mdl2eRig {
  kernel::VirtualTimeExecutor ex;
  os::Node node{ex, {"bot"}};
  Mdl2eSensor* sensor = nullptr;
  Mdl2eTask* ctl = nullptr;
  Mdl2eRecorder* rec = nullptr;
  os::TaskId sensor_id, ctl_id, rec_id;

  explicit Mdl2eRig(std::string_view source, int ctl_priority = 2, Mdl2eTaskOptions options = {},
                    DeviceLookup devices = {}) {
    auto s = std::make_unique<Mdl2eSensor>();
    sensor = s.get();
    sensor_id = *node.create("ir", std::move(s), {.priority = 1, .period = 10ms});
    auto r = std::make_unique<Mdl2eRecorder>();
    rec = r.get();
    rec_id = *node.create("rec", std::move(r), {.queue_capacity = 64});
    ctl_id = add_controller("ctl", source, ctl_priority, options, std::move(devices));
  }
  os::TaskId add_controller(std::string name, std::string_view source, int priority = 2, Mdl2eTaskOptions options = {},
                            DeviceLookup devices = {}) {
    auto c = Mdl2eTask::create(compile(source), options, std::move(devices));
    EXPECT_TRUE(c.ok()) << (c.ok() ? std::string() : c.error());
    ctl = c->get();
    auto id = *node.create(std::move(name), std::move(c).value(),
                           {.priority = priority, .period = 30ms, .queue_capacity = 4});
    EXPECT_TRUE(node.hook(sensor_id, id, {.policy = os::QueuePolicy::kKeepNewest}));
    EXPECT_TRUE(node.hook(id, rec_id, {.policy = os::QueuePolicy::kKeepNewest}));
    return id;
  }
  std::size_t warnings(std::string_view text) {
    std::size_t n = 0;
    for (const auto& e : node.log().since(0))
      if (e.level == os::LogLevel::kWarn && e.text.find(text) != std::string::npos) ++n;
    return n;
  }
};

TEST(Mdl2eTask, SendsNothingBeforeTheFirstSensorVectorThenReactsAtItsInstant) {
  Mdl2eRig rig(kAvoid);
  rig.sensor->script(ms(50), kClearIr);
  rig.sensor->script(ms(70), kWall);
  rig.ex.run_until(ms(49));
  EXPECT_EQ(rig.rec->size(), 0u);  // ticks at 30 ms had nothing to step on
  EXPECT_EQ(rig.ctl->stats().idle_ticks, 1u);
  EXPECT_FALSE(rig.ctl->state().started);

  rig.ex.run_until(ms(50));
  auto first = rig.rec->at(ms(50));  // the plan starts at the vector's own instant
  ASSERT_EQ(first.size(), 1u);
  EXPECT_EQ(first[0].left, 100);
  EXPECT_EQ(first[0].right, 100);
  EXPECT_EQ(rig.ctl->state().active_path, "p/cruise/forward");

  rig.ex.run_until(ms(70));
  auto wall = rig.rec->at(ms(70));  // between two ticks (60, 90): the message itself steps
  ASSERT_EQ(wall.size(), 1u);
  EXPECT_EQ(wall[0].left, -80);
  EXPECT_EQ(wall[0].right, 80);
  EXPECT_EQ(rig.ctl->state().active_path, "p/cruise/turn");
  const Mdl2eStats s = rig.ctl->stats();
  EXPECT_EQ(s.sensor_messages, 2u);
  EXPECT_EQ(s.steps, 3u);  // 50 (vector), 60 (tick), 70 (vector)
  EXPECT_EQ(s.tick_steps, 1u);
}

TEST(Mdl2eTask, StepsAtItsPeriodWithoutNewDataAndRunsTimersInVirtualTime) {
  Mdl2eRig rig(R"(
sensor ir[7]
plan p { atom forward(100) for 100ms  atom turn(50) for 200ms  atom backward(20) }
)");
  rig.sensor->script(ms(10), kClearIr);  // one vector, then silence
  rig.ex.run_until(ms(400));
  const auto cmds = rig.rec->commands();
  ASSERT_EQ(cmds.size(), 1u + 13u);  // at 10 ms, then every tick 30 .. 390 ms
  EXPECT_EQ(cmds[0].time, ms(10));
  for (std::size_t k = 1; k < cmds.size(); ++k) EXPECT_EQ(cmds[k].time, ms(30 * static_cast<long long>(k)));
  // forward until 110 ms, turn until 310 ms, then backward: as seen at the ticks.
  for (const auto& c : cmds) {
    const long long t = std::chrono::duration_cast<std::chrono::milliseconds>(c.time).count();
    const float expect_left = t < 110 ? 100.0f : t < 310 ? -50.0f : -20.0f;
    EXPECT_EQ(c.left, expect_left) << "t=" << t;
  }
}

TEST(Mdl2eTask, TickThenVectorAtOneInstantStepsTwiceTheLastOnTheNewVector) {
  Mdl2eRig rig(kAvoid, /*ctl_priority=*/2);  // above the sensor (1): its tick runs first
  rig.sensor->script(ms(10), kClearIr);
  rig.sensor->script(ms(90), kWall);
  rig.ex.run_until(ms(90));
  const auto both = rig.rec->at(ms(90));
  ASSERT_EQ(both.size(), 2u);
  EXPECT_EQ(both[0].left, 100);  // the tick, on the vector of 10 ms
  EXPECT_EQ(both[1].left, -80);  // the new vector
  EXPECT_EQ(rig.ctl->stats().skipped_ticks, 0u);
}

TEST(Mdl2eTask, VectorThenTickAtOneInstantStepsOnce) {
  Mdl2eRig rig(kAvoid, /*ctl_priority=*/0);  // below the sensor (1): the vector comes first
  rig.sensor->script(ms(10), kClearIr);
  rig.sensor->script(ms(90), kWall);
  rig.ex.run_until(ms(90));
  const auto one = rig.rec->at(ms(90));
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one[0].left, -80);
  EXPECT_EQ(rig.ctl->stats().skipped_ticks, 1u);

  // A bad vector handed over before a tick: the tick steps on the last good one.
  rig.ex.run_until(ms(179));
  const std::uint64_t tick_steps = rig.ctl->stats().tick_steps;
  rig.sensor->script(ms(180), {1, 2, 3});
  rig.ex.run_until(ms(180));
  const auto kept = rig.rec->at(ms(180));
  ASSERT_EQ(kept.size(), 1u);
  EXPECT_EQ(kept[0].left, -80);
  EXPECT_EQ(rig.ctl->stats().wrong_count, 1u);
  EXPECT_EQ(rig.ctl->stats().tick_steps, tick_steps + 1);
  EXPECT_EQ(rig.ctl->stats().skipped_ticks, 1u);

  // A bad vector waiting in the queue at a tick: the tick leaves its step to it, and the step is
  // not lost to it: it is taken on the last good vector, counted as the tick's.
  rig.ex.run_until(ms(269));
  const std::uint64_t tick_steps_before = rig.ctl->stats().tick_steps;
  rig.sensor->script(ms(270), {1, 2, 3}, rig.ctl_id);
  rig.ex.run_until(ms(270));
  const auto deferred = rig.rec->at(ms(270));
  ASSERT_EQ(deferred.size(), 1u);
  EXPECT_EQ(deferred[0].left, -80);
  EXPECT_EQ(rig.ctl->stats().wrong_count, 2u);
  EXPECT_EQ(rig.ctl->stats().skipped_ticks, 2u);
  EXPECT_EQ(rig.ctl->stats().tick_steps, tick_steps_before + 1);
}

TEST(Mdl2eTask, ExternalBitsReactAtOnceAndThePlanEndGivesZeros) {
  Mdl2eRig rig(kAvoid);
  rig.sensor->script(ms(10), kClearIr);
  rig.ex.run_until(ms(100));
  os::Message bump;
  bump.port = kExternalPort;
  bump.payload = os::Payload{0.0f, 1.0f};
  ASSERT_TRUE(rig.node.post(rig.ctl_id, bump));
  rig.ex.run_for(0ms);
  EXPECT_EQ(rig.rec->last().time, ms(100));
  EXPECT_EQ(rig.rec->last().left, -40);  // backward(40) for 100 ms
  EXPECT_EQ(rig.ctl->state().external, 1u);
  EXPECT_EQ(rig.ctl->state().active_path, "p/backward");
  rig.ex.run_until(ms(300));
  // Ended at 200 ms (seen at the tick of 210 ms): zeros at every tick from then on.
  std::size_t zeros = 0;
  for (const auto& c : rig.rec->commands()) {
    if (c.time < ms(210)) {
      EXPECT_NE(c.left, 0.0f);
    }
    if (c.time >= ms(210)) {
      EXPECT_EQ(c.left, 0.0f);
      EXPECT_EQ(c.right, 0.0f);
      ++zeros;
    }
  }
  EXPECT_EQ(zeros, 4u);  // 210, 240, 270, 300
  const Mdl2eState st = rig.ctl->state();
  EXPECT_TRUE(st.ended);
  EXPECT_EQ(st.active_path, "");
  std::size_t ended_logs = 0;
  for (const auto& e : rig.node.log().since(0))
    if (e.text.find("ended") != std::string::npos) ++ended_logs;
  EXPECT_EQ(ended_logs, 1u);
}

TEST(Mdl2eTask, BadMessagesAreIgnoredCountedAndWarnedAtALimitedRate) {
  Mdl2eRig rig(kAvoid);
  rig.sensor->script(ms(10), kClearIr);
  rig.ex.run_until(ms(20));
  const std::size_t before = rig.rec->size();
  auto post = [&](os::Port port, std::vector<float> v) {
    os::Message m;
    m.port = port;
    m.payload.assign(v);
    ASSERT_TRUE(rig.node.post(rig.ctl_id, m));
    rig.ex.run_for(0ms);
  };
  post(kSensorPort, {0, 0, 3000, 0, 0, 0});  // 6 values
  post(kSensorPort, {0, 0, 3000, 0, 0, 0, 0, 0});
  post(kSensorPort, {0, 0, 3000, kNaN, 0, 0, 0});
  post(kSensorPort, {0, 0, 3000, std::numeric_limits<float>::infinity(), 0, 0, 0});
  post(kExternalPort, {70, 1});
  post(kExternalPort, {0, 0.5f});
  post(kExternalPort, {0.5f, 1});
  post(kExternalPort, {0});
  post(9, {1, 2});
  os::Message blob;
  struct Text : os::Blob {
    std::uint32_t kind() const override { return 42; }
  };
  blob.payload = os::Payload(std::make_shared<Text>());
  ASSERT_TRUE(rig.node.post(rig.ctl_id, blob));
  rig.ex.run_for(0ms);

  EXPECT_EQ(rig.rec->size(), before);  // nothing stepped on bad input
  const Mdl2eStats s = rig.ctl->stats();
  EXPECT_EQ(s.wrong_count, 2u);
  EXPECT_EQ(s.not_finite, 2u);
  EXPECT_EQ(s.bad_external, 4u);
  EXPECT_EQ(s.other, 2u);
  EXPECT_EQ(s.ignored, 10u);
  EXPECT_EQ(rig.warnings("ignored"), 1u);  // all within one warn interval
  EXPECT_EQ(rig.node.info(rig.ctl_id)->state, os::TaskState::kRunning);

  // The last good vector (clear) still drives; a bad one later in another interval warns again
  // and counts what it stands for.
  rig.ex.run_until(ms(1200));
  EXPECT_EQ(rig.rec->last().left, 100);
  post(kSensorPort, {kNaN, 0, 0, 0, 0, 0, 0});
  EXPECT_EQ(rig.warnings("ignored"), 2u);
  EXPECT_EQ(rig.ctl->stats().ignored, 11u);
}

TEST(Mdl2eTask, TaskActionsStartSuspendResumeDeleteAndAMissingTaskIsOnlyWarned) {
  Mdl2eRig rig(R"(
sensor ir[7]
plan p {
  task start logger
  atom forward(10) for 100ms
  task suspend worker
  atom forward(20) for 100ms
  task resume worker
  task delete victim
  task start ghost
  task start worker
  atom forward(30)
}
)");
  auto logger = *rig.node.create("logger", std::make_unique<Idle>(), {.autostart = false});
  auto worker = *rig.node.create("worker", std::make_unique<Idle>());
  auto victim = *rig.node.create("victim", std::make_unique<Idle>());
  rig.sensor->script(ms(10), kClearIr);
  rig.ex.run_until(ms(10));
  EXPECT_EQ(rig.node.info(logger)->state, os::TaskState::kRunning);
  EXPECT_EQ(rig.node.info(worker)->state, os::TaskState::kRunning);
  rig.ex.run_until(ms(120));  // forward(10) ended at 110 ms, seen at the tick of 120 ms
  EXPECT_EQ(rig.node.info(worker)->state, os::TaskState::kSuspended);
  EXPECT_EQ(rig.rec->last().left, 20);
  rig.ex.run_until(ms(210));
  EXPECT_EQ(rig.node.info(worker)->state, os::TaskState::kRunning);
  EXPECT_FALSE(rig.node.find("victim").has_value());
  EXPECT_FALSE(rig.node.info(victim).has_value());
  EXPECT_EQ(rig.rec->last().left, 30);
  EXPECT_EQ(rig.node.info(rig.ctl_id)->state, os::TaskState::kRunning);  // not faulted
  const Mdl2eStats s = rig.ctl->stats();
  EXPECT_EQ(s.task_actions, 5u);  // start of a running task counts as done
  EXPECT_EQ(s.task_action_failures, 1u);
  EXPECT_EQ(rig.warnings("ghost"), 1u);
}

// A docking connector as a program sees it: `latch` and `unlatch`, and `grip` with a force in
// 0..10; it keeps what it was told.
class Mdl2eConnector : public io::Device {
 public:
  std::vector<std::string> heard;
  Mdl2eConnector() : io::Device("connector_front") {
    add_ioctl({"latch", std::nullopt, "dock"}, [this](const os::ParamValue*) -> kernel::Result<std::string> {
      heard.push_back("latch");
      return std::string("docked");
    });
    add_ioctl({"unlatch", std::nullopt, "undock"}, [this](const os::ParamValue*) -> kernel::Result<std::string> {
      heard.push_back("unlatch");
      return kernel::Error{"not docked"};
    });
    os::ParamSpec force{
        .name = "force", .type = os::ParamType::kReal, .default_value = 0.0, .min = 0, .max = 10, .doc = "N"};
    add_ioctl({"grip", force, "grip"}, [this](const os::ParamValue* v) -> kernel::Result<std::string> {
      heard.push_back("grip " + std::to_string(std::get<double>(*v)));
      return std::string("ok");
    });
  }
  kernel::Status open() override { return {}; }
  void close() override {}
  bool is_open() const override { return true; }
};

TEST(Mdl2eTask, DeviceActionsSendTheirCommandToTheRobotsDeviceAndFailuresAreOnlyWarned) {
  auto connector = std::make_shared<Mdl2eConnector>();
  DeviceLookup devices = [connector](std::string_view name) -> std::shared_ptr<io::Device> {
    return name == "connector_front" ? connector : nullptr;
  };
  Mdl2eRig rig(R"(
sensor ir[7]
plan p {
  device connector_front latch
  atom forward(10) for 100ms
  device connector_front grip 2.5
  device connector_front unlatch
  device connector_back latch
  device connector_front grip 11
  atom forward(30)
}
)",
               2, {}, devices);
  rig.sensor->script(ms(10), kClearIr);
  rig.ex.run_until(ms(10));
  EXPECT_EQ(connector->heard, std::vector<std::string>{"latch"});
  EXPECT_EQ(rig.rec->last().left, 10);
  rig.ex.run_until(ms(120));
  EXPECT_EQ(connector->heard, (std::vector<std::string>{"latch", "grip 2.500000", "unlatch"}));
  EXPECT_EQ(rig.rec->last().left, 30);
  const Mdl2eStats s = rig.ctl->stats();
  EXPECT_EQ(s.task_actions, 2u);          // latch, grip 2.5
  EXPECT_EQ(s.task_action_failures, 3u);  // refused unlatch, missing connector_back, grip out of range
  EXPECT_EQ(rig.warnings("device connector_front unlatch not done: not docked"), 1u);
  EXPECT_EQ(rig.node.info(rig.ctl_id)->state, os::TaskState::kRunning);
  std::size_t infos = 0;
  for (const auto& e : rig.node.log().since(0))
    if (e.level == os::LogLevel::kInfo && e.text == "device connector_front latch: docked") ++infos;
  EXPECT_EQ(infos, 1u);
}

TEST(Mdl2eTask, DeviceActionsWithoutDevicesFailWithAWarning) {
  Mdl2eRig rig("sensor ir[7]\nplan p {\n  device connector_front latch\n  atom forward(30)\n}\n");
  rig.sensor->script(ms(10), kClearIr);
  rig.ex.run_until(ms(10));
  EXPECT_EQ(rig.ctl->stats().task_action_failures, 1u);
  EXPECT_EQ(rig.warnings("no device named 'connector_front'"), 1u);
  EXPECT_EQ(rig.rec->last().left, 30);
}

TEST(Mdl2eTask, SuspendedItSendsNothingAndResumedItGoesOn) {
  Mdl2eRig rig(kAvoid);
  rig.sensor->script(ms(10), kClearIr);
  rig.ex.run_until(ms(100));
  ASSERT_TRUE(rig.node.suspend(rig.ctl_id));
  const std::size_t before = rig.rec->size();
  rig.sensor->script(ms(150), kWall);  // queued while suspended
  rig.ex.run_until(ms(300));
  EXPECT_EQ(rig.rec->size(), before);
  ASSERT_TRUE(rig.node.resume(rig.ctl_id));
  rig.ex.run_for(0ms);
  // The queued vector is handled at resume, and ticks restart one period later.
  ASSERT_EQ(rig.rec->size(), before + 1);
  EXPECT_EQ(rig.rec->last().time, ms(300));
  EXPECT_EQ(rig.rec->last().left, -80);
  rig.ex.run_until(ms(330));
  EXPECT_EQ(rig.rec->size(), before + 2);
  EXPECT_EQ(rig.rec->last().time, ms(330));
}

TEST(Mdl2eTask, ReplacingTheControllerAtRuntimeKeepsTheOutputFlowing) {
  Mdl2eRig rig(kAvoid);
  for (long long t = 10; t <= 600; t += 10) rig.sensor->script(ms(t), kClearIr);
  rig.ex.run_until(ms(300));
  ASSERT_TRUE(rig.node.remove(rig.ctl_id));
  rig.add_controller("ctl2", R"(
sensor ir[7]
plan q loop { atom wheels(30, 60) }
)");
  rig.ex.run_until(ms(600));
  Time last{0};
  bool seen_new = false;
  for (const auto& c : rig.rec->commands()) {
    EXPECT_LE(c.time - last, 30ms) << "gap before " << c.time.count();
    last = c.time;
    if (c.time > ms(300)) {
      EXPECT_EQ(c.left, 30);
      EXPECT_EQ(c.right, 60);
      seen_new = true;
    } else {
      EXPECT_EQ(c.left, 100);
    }
  }
  EXPECT_TRUE(seen_new);
  EXPECT_EQ(rig.rec->last().time, ms(600));
}

TEST(Mdl2eTask, SpeedsAreClampedToTheLimitAndBadOptionsAreRefused) {
  Mdl2eRig rig(R"(
sensor ir[7]
plan p { atom wheels(900, -2000) }
)",
               2, {.speed_limit = 500});
  rig.sensor->script(ms(10), kClearIr);
  rig.ex.run_until(ms(10));
  EXPECT_EQ(rig.rec->last().left, 500);
  EXPECT_EQ(rig.rec->last().right, -500);
  EXPECT_EQ(rig.ctl->stats().clamped, 2u);
  EXPECT_TRUE(
      Mdl2eTask::create(compile("sensor a[1] plan p { atom stop }"), {.speed_limit = 0}).error().find("speed_limit") !=
      std::string::npos);
  auto big = compile("sensor a[33] plan p { atom stop }");
  EXPECT_NE(Mdl2eTask::create(big).error().find("33 sensor values"), std::string::npos);
}

TEST(Mdl2eTask, AProgramWithoutSensorsStartsAtItsFirstTickAndRunsUnderTheThreadExecutor) {
  kernel::ThreadExecutor ex;
  os::Node node(ex, {"bot"});
  auto rec_task = std::make_unique<Mdl2eRecorder>();
  Mdl2eRecorder* rec = rec_task.get();
  auto rec_id = *node.create("rec", std::move(rec_task), {.queue_capacity = 64});
  auto c = Mdl2eTask::create(compile("plan p loop { atom forward(10) for 20ms  atom turn(5) for 20ms }"));
  ASSERT_TRUE(c);
  Mdl2eTask* ctl = c->get();
  auto ctl_id = *node.create("ctl", std::move(c).value(), {.period = 2ms, .autostart = false});
  ASSERT_TRUE(node.hook(ctl_id, rec_id));
  ASSERT_TRUE(node.start(ctl_id));
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  std::string path;
  while (rec->size() < 40 && std::chrono::steady_clock::now() < deadline) {
    path = ctl->state().active_path;  // read while the controller runs on its own thread
    std::this_thread::sleep_for(1ms);
  }
  EXPECT_GE(rec->size(), 40u);
  bool saw_forward = false, saw_turn = false;
  for (const auto& cmd : rec->commands()) {
    saw_forward = saw_forward || (cmd.left == 10 && cmd.right == 10);
    saw_turn = saw_turn || (cmd.left == -5 && cmd.right == 5);
  }
  EXPECT_TRUE(saw_forward);
  EXPECT_TRUE(saw_turn);
  node.clear();
}

// The counters have one writer (the controller's context) and are read here, on another thread,
// while it runs: no lock (kernel/counter.hpp), so the thread sanitizer build checks the pattern.
TEST(Mdl2eTask, StatsReadFromAnotherThreadWhileItRunsNeverGoBack) {
  kernel::ThreadExecutor ex;
  os::Node node(ex, {"bot"});
  auto rec_id = *node.create("rec", std::make_unique<Mdl2eRecorder>(), {.queue_capacity = 64});
  auto c = Mdl2eTask::create(compile("plan p loop { atom forward(10) for 4ms  atom turn(5) for 4ms }"));
  ASSERT_TRUE(c);
  Mdl2eTask* ctl = c->get();
  auto ctl_id = *node.create("ctl", std::move(c).value(), {.period = 1ms});
  ASSERT_TRUE(node.hook(ctl_id, rec_id));
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  Mdl2eStats last;
  std::size_t reads = 0;
  while (last.steps < 50 && std::chrono::steady_clock::now() < deadline) {
    const Mdl2eStats s = ctl->stats();
    EXPECT_GE(s.steps, last.steps);
    EXPECT_GE(s.tick_steps, last.tick_steps);
    EXPECT_GE(s.clamped, last.clamped);
    EXPECT_EQ(s.ignored, 0u);
    const Mdl2eState st = ctl->state();
    EXPECT_GE(st.stats.steps, s.steps);
    last = s;
    ++reads;
    std::this_thread::yield();
  }
  node.clear();
  EXPECT_GE(last.steps, 50u);
  EXPECT_GT(reads, 1u);
}

// --- the task type ---------------------------------------------------------------------------------

std::string read_file(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

ControlResources scenario_files() {
  ControlResources r;
  r.read_program = [](std::string_view ref) -> kernel::Result<std::string> {
    if (ref.find('/') != std::string_view::npos) return kernel::Error{"no such program"};
    std::ifstream f(std::string(SYMB_SCENARIO_DIR) + "/" + std::string(ref));
    if (!f) return kernel::Error{"no such program"};
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
  };
  return r;
}

kernel::Result<os::TaskId> create(os::Node& node, std::string name, std::string_view params) {
  auto a = os::parse_param_assignments(params);
  if (!a) return kernel::Error{a.error()};
  return node.create("mdl2e", std::move(name), *a);
}

TEST(ControlTaskTypes, RegistersMdl2eWithItsSchemaAndDefaults) {
  os::TaskTypeRegistry registry;
  ASSERT_TRUE(register_control_task_types(registry, scenario_files()));
  const os::TaskType* t = registry.find("mdl2e");
  ASSERT_NE(t, nullptr);
  EXPECT_EQ(t->defaults.priority, 0);  // below the sensor type's 1: the newest data first
  EXPECT_EQ(t->defaults.period, kernel::Duration{30ms});
  EXPECT_EQ(t->defaults.queue_capacity, 4u);
  ASSERT_NE(t->param("program"), nullptr);
  EXPECT_EQ(t->param("program")->type, os::ParamType::kString);
  ASSERT_NE(t->param("speed_limit"), nullptr);
  EXPECT_EQ(std::get<double>(t->param("speed_limit")->default_value), 500.0);
  EXPECT_FALSE(register_control_task_types(registry, scenario_files()));  // name taken
}

TEST(ControlTaskTypes, CreationErrorsNameTheProgramAndTheLineAndColumn) {
  os::TaskTypeRegistry registry;
  ControlResources r;
  r.read_program = [](std::string_view ref) -> kernel::Result<std::string> {
    if (ref == "broken") return std::string("sensor ir[7]\nplan p {\n  atom forwrd(100)\n}\n");
    if (ref == "ok") return std::string("plan p { atom wheels(300, -300) }\n");
    return kernel::Error{"no such program"};
  };
  ASSERT_TRUE(register_control_task_types(registry, r));
  kernel::VirtualTimeExecutor ex;
  os::Node node(ex, {.name = "bot", .types = &registry});
  auto e = create(node, "c", "program=broken");
  ASSERT_FALSE(e);
  EXPECT_NE(e.error().find("program 'broken': 3:8:"), std::string::npos) << e.error();
  EXPECT_NE(e.error().find("forward"), std::string::npos) << e.error();  // did you mean
  e = create(node, "c", "program=missing");
  ASSERT_FALSE(e);
  EXPECT_NE(e.error().find("program 'missing': no such program"), std::string::npos) << e.error();
  e = create(node, "c", "");
  ASSERT_FALSE(e);
  EXPECT_NE(e.error().find("program="), std::string::npos) << e.error();
  e = create(node, "c", "program=ok speed_limit=0");
  EXPECT_FALSE(e);  // out of the schema's range
  EXPECT_EQ(node.task_count(), 0u);

  os::TaskTypeRegistry bare;
  ASSERT_TRUE(register_control_task_types(bare, {}));
  os::Node node2(ex, {.name = "bot2", .types = &bare});
  e = create(node2, "c", "program=ok");
  ASSERT_FALSE(e);
  EXPECT_NE(e.error().find("read_program"), std::string::npos) << e.error();

  // Runtime parameters: the limit changes, the program does not.
  auto ok = create(node, "c", "program=ok");
  ASSERT_TRUE(ok) << ok.error();
  auto rec_task = std::make_unique<Mdl2eRecorder>();
  Mdl2eRecorder* rec = rec_task.get();
  ASSERT_TRUE(node.hook(*ok, *node.create("rec", std::move(rec_task))));
  ex.run_for(30ms);  // a program without sensors starts at its first tick
  EXPECT_EQ(rec->last().left, 300);
  EXPECT_TRUE(node.set_parameter(*ok, "speed_limit", "200"));
  ex.run_for(30ms);
  EXPECT_EQ(rec->last().left, 200);
  EXPECT_EQ(rec->last().right, -200);
  ASSERT_TRUE(node.set_parameter(*ok, "program", "broken"));  // passes the schema ...
  ex.run_for(1ms);
  bool refused = false;  // ... and the task refuses it, in the log
  for (const auto& entry : node.log().since(0))
    refused = refused || entry.text.find("keeps its program") != std::string::npos;
  EXPECT_TRUE(refused);
  EXPECT_EQ(node.parameters(*ok)->string("program"), "ok");
}

TEST(ControlTaskTypes, TasksOfOneRegistryShareTheCompiledProgramOfOneText) {
  std::string second = "plan p { atom wheels(100, 100) }\n";
  ControlResources r;
  r.read_program = [&](std::string_view ref) -> kernel::Result<std::string> {
    if (ref == "first" || ref == "same_text") return std::string("plan p { atom wheels(300, -300) }\n");
    if (ref == "second") return second;
    return kernel::Error{"no such program"};
  };
  os::TaskTypeRegistry registry, other_registry;
  ASSERT_TRUE(register_control_task_types(registry, r));
  ASSERT_TRUE(register_control_task_types(other_registry, r));
  const auto make = [](const os::TaskTypeRegistry& from, std::string_view params) -> std::unique_ptr<os::Task> {
    const os::TaskType* type = from.find("mdl2e");
    auto given = os::parse_param_assignments(params);
    auto values = from.resolve(*type, *given);
    auto task = type->make(*values);
    return task ? std::move(task).value() : nullptr;
  };
  const auto program_of = [](const std::unique_ptr<os::Task>& t) { return &static_cast<Mdl2eTask&>(*t).program(); };
  auto a = make(registry, "program=first"), b = make(registry, "program=same_text");
  auto c = make(registry, "program=second"), d = make(other_registry, "program=first");
  ASSERT_TRUE(a && b && c && d);
  EXPECT_EQ(program_of(a), program_of(b));  // one text, one compiled program
  EXPECT_NE(program_of(a), program_of(c));
  EXPECT_NE(program_of(a), program_of(d));  // registries (sessions) share nothing
  // A changed file is compiled anew; tasks made before keep the program they run.
  const mdl2e::Program* before = program_of(c);
  second = "plan p { atom wheels(50, 50) }\n";
  auto e = make(registry, "program=second");
  ASSERT_TRUE(e);
  EXPECT_NE(program_of(e), before);
  EXPECT_EQ(program_of(c), before);
  // A program no task runs any more is not kept: the next task gets it compiled again.
  c.reset();
  e.reset();
  auto f = make(registry, "program=second");
  ASSERT_TRUE(f);
  EXPECT_EQ(static_cast<Mdl2eTask&>(*f).program(), *mdl2e::compile_source(second));
}

TEST(ControlTaskTypes, ShippedObstacleAvoidanceDrivesTheRobotThroughTheNode) {
  ASSERT_FALSE(read_file(std::string(SYMB_SCENARIO_DIR) + "/obstacle_avoidance.mdl2e").empty());
  os::TaskTypeRegistry registry;
  ASSERT_TRUE(register_control_task_types(registry, scenario_files()));
  kernel::VirtualTimeExecutor ex;
  os::Node node(ex, {.name = "thymio", .types = &registry});
  auto sensor_task = std::make_unique<Mdl2eSensor>();
  Mdl2eSensor* sensor = sensor_task.get();
  auto ir = *node.create("ir", std::move(sensor_task), os::TaskOptions{.priority = 1, .period = 30ms});
  auto rec_task = std::make_unique<Mdl2eRecorder>();
  Mdl2eRecorder* rec = rec_task.get();
  auto wheels = *node.create("wheels", std::move(rec_task), {.queue_capacity = 64});
  auto logger = *node.create("obstacle_logger", std::make_unique<Idle>(), {.autostart = false});
  auto ctl = create(node, "avoid", "program=obstacle_avoidance.mdl2e speed_limit=90");
  ASSERT_TRUE(ctl) << ctl.error();
  EXPECT_EQ(node.info(*ctl)->period, kernel::Duration{30ms});
  EXPECT_EQ(node.info(*ctl)->priority, 0);
  ASSERT_TRUE(node.hook(ir, *ctl, {.policy = os::QueuePolicy::kKeepNewest}));
  ASSERT_TRUE(node.hook(*ctl, wheels));

  // IR at 30 ms intervals, from the sensor's first tick: clear, a wall in front from 300 ms to
  // 600 ms, clear again; bumped at 900 ms.
  for (long long t = 30; t <= 1800; t += 30) sensor->script(ms(t), t >= 300 && t < 600 ? kWall : kClearIr);
  ex.run_until(ms(30));
  EXPECT_EQ(node.info(logger)->state, os::TaskState::kRunning);  // task start obstacle_logger
  EXPECT_EQ(rec->last().left, 90);                               // forward(100), clamped to speed_limit=90
  EXPECT_EQ(rec->last().right, 90);
  ex.run_until(ms(300));
  EXPECT_EQ(rec->last().time, ms(300));
  EXPECT_EQ(rec->last().left, -80);  // turn(80): left
  EXPECT_EQ(rec->last().right, 80);
  ex.run_until(ms(600));
  EXPECT_EQ(rec->last().left, 90);
  // Under the defaults the vector is queued before the controller's tick at each instant: one
  // command per period, each from that period's vector (the wall from 300 ms turns at 300 ms).
  EXPECT_EQ(rec->size(), 20u);
  for (long long t = 30; t <= 600; t += 30) ASSERT_EQ(rec->at(ms(t)).size(), 1u) << t << " ms";
  EXPECT_EQ(rec->at(ms(300))[0].left, -80);
  EXPECT_EQ(rec->at(ms(270))[0].left, 90);
  ex.run_until(ms(899));
  os::Message bump;
  bump.port = kExternalPort;
  bump.payload = os::Payload{0.0f, 1.0f};
  ex.run_until(ms(900));
  ASSERT_TRUE(node.post(*ctl, bump));
  ex.run_for(0ms);
  EXPECT_EQ(rec->last().left, -50);  // backward(50) for 500 ms
  ex.run_until(ms(1500));
  EXPECT_EQ(rec->last().left, 0);  // plan over: task suspend obstacle_logger, zeros
  EXPECT_EQ(rec->last().right, 0);
  EXPECT_EQ(node.info(logger)->state, os::TaskState::kSuspended);
}

// A program with a long and/or chain, created at runtime beside a running controller (as a shell
// `create mdl2e` does): one as long as the byte code holds is created, a longer one is refused
// with its line and column, and the running controller drives on.
TEST(ControlTaskTypes, ALongInterruptChainIsCreatedOrRefusedWhileTheRobotRuns) {
  const auto chain = [](int terms) {
    std::string s = "interrupt a = external\nplan p { atom wheels(100, 100) until a";
    for (int i = 1; i < terms; ++i) s += " or a";
    return s + " }\n";
  };
  os::TaskTypeRegistry registry;
  ControlResources r;
  r.read_program = [&](std::string_view ref) -> kernel::Result<std::string> {
    if (ref == "long") return chain(19000);
    if (ref == "longer") return chain(150000);
    return std::string("plan p { atom wheels(300, 300) }\n");
  };
  ASSERT_TRUE(register_control_task_types(registry, r));
  kernel::VirtualTimeExecutor ex;
  os::Node node(ex, {.name = "bot", .types = &registry});
  auto running = create(node, "running", "program=ok");
  ASSERT_TRUE(running) << running.error();
  auto rec_task = std::make_unique<Mdl2eRecorder>();
  Mdl2eRecorder* rec = rec_task.get();
  ASSERT_TRUE(node.hook(*running, *node.create("rec", std::move(rec_task))));
  ex.run_for(30ms);
  auto longer = create(node, "c2", "program=longer");
  ASSERT_FALSE(longer);
  EXPECT_NE(longer.error().find("program 'longer': 2:"), std::string::npos) << longer.error();
  EXPECT_NE(longer.error().find("interrupt expressions are too large in all"), std::string::npos) << longer.error();
  auto created = create(node, "c1", "program=long");
  EXPECT_TRUE(created) << created.error();
  const auto before = rec->size();
  ex.run_for(30ms);
  EXPECT_GT(rec->size(), before);
  EXPECT_EQ(rec->last().left, 300);
  EXPECT_EQ(node.task_count(), 3u);
}

}  // namespace
}  // namespace symb::control
