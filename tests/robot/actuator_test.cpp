#include "symb/robot/actuator.hpp"

#include <limits>
#include <tuple>

#include <gtest/gtest.h>

#include "symb/io/bytes.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"

#include "fakes.hpp"

namespace symb::robot {
namespace {

using namespace std::chrono_literals;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// Three LEDs, brightness 0..1; remembers what reached the "hardware".
class FakeLeds final : public Actuator {
 public:
  explicit FakeLeds(DeviceThreads threads = DeviceThreads::kAny)
      : Actuator("leds", {{"red", "", 0, 1}, {"green", "", 0, 1}, {"blue", "", 0, 1}}, threads) {}
  std::vector<std::vector<float>> applied;
  bool fail = false;

 protected:
  kernel::Status apply(std::span<const float> v) override {
    if (fail) return kernel::Error{"i2c nack"};
    applied.emplace_back(v.begin(), v.end());
    return {};
  }
};

TEST(Actuator, AppliesAtOnceClampedAndKeepsTheOutputOnBadInput) {
  FakeLeds leds;
  EXPECT_EQ(leds.output(), (std::vector<float>{0, 0, 0}));
  const std::vector<float> on = {0.5f, 2.0f, -1.0f};
  EXPECT_EQ(leds.set(on).error(), "actuator 'leds' is closed");
  ASSERT_TRUE(leds.open());
  auto r = leds.set(on);
  ASSERT_TRUE(r);
  EXPECT_EQ(*r, 2u);
  EXPECT_EQ(leds.output(), (std::vector<float>{0.5f, 1, 0}));
  ASSERT_EQ(leds.applied.size(), 1u);
  EXPECT_EQ(leds.applied[0], leds.output());

  EXPECT_EQ(leds.set(std::vector<float>{0.1f, kNaN, 0.1f}).error(), "actuator 'leds': NaN for channel 'green'");
  EXPECT_EQ(leds.set(std::vector<float>{0.1f}).error(), "actuator 'leds' takes 3 values, not 1");
  leds.fail = true;
  EXPECT_EQ(leds.set(std::vector<float>{0.2f, 0.2f, 0.2f}).error(), "actuator 'leds': i2c nack");
  EXPECT_EQ(leds.output(), (std::vector<float>{0.5f, 1, 0}));  // nothing half applied
  EXPECT_EQ(leds.applied.size(), 1u);

  const ActuatorStats s = leds.stats();
  EXPECT_EQ(s.commands, 5u);
  EXPECT_EQ(s.applied, 1u);
  EXPECT_EQ(s.rejected, 2u);
  EXPECT_EQ(s.not_open, 1u);
  EXPECT_EQ(s.driver_errors, 1u);
  EXPECT_EQ(s.clamped_values, 2u);
}

// Without its lock (a simulated robot's, called from one context at a time) an actuator conditions,
// applies, refuses and counts exactly as with it.
TEST(Actuator, OneCallerAtATimeNeedsNoLockAndBehavesTheSame) {
  FakeLeds locked;
  FakeLeds unlocked(DeviceThreads::kOneAtATime);
  EXPECT_EQ(locked.threads(), DeviceThreads::kAny);
  EXPECT_EQ(unlocked.threads(), DeviceThreads::kOneAtATime);
  for (FakeLeds* leds : {&locked, &unlocked}) {
    EXPECT_FALSE(leds->set(std::vector<float>{1, 1, 1}));  // closed
    ASSERT_TRUE(leds->open());
    EXPECT_EQ(*leds->set(std::vector<float>{0.5f, 2.0f, -1.0f}), 2u);
    EXPECT_FALSE(leds->set(std::vector<float>{kNaN, 0, 0}));
    leds->fail = true;
    EXPECT_FALSE(leds->set(std::vector<float>{0.1f, 0.1f, 0.1f}));
  }
  EXPECT_EQ(unlocked.output(), (std::vector<float>{0.5f, 1.0f, 0.0f}));
  EXPECT_EQ(unlocked.output(), locked.output());
  EXPECT_EQ(unlocked.applied, locked.applied);
  const ActuatorStats a = locked.stats(), b = unlocked.stats();
  EXPECT_EQ(b.commands, 4u);
  EXPECT_EQ(b.applied, 1u);
  EXPECT_EQ(std::tie(a.commands, a.applied, a.rejected, a.not_open, a.driver_errors, a.clamped_values),
            std::tie(b.commands, b.applied, b.rejected, b.not_open, b.driver_errors, b.clamped_values));
}

TEST(Actuator, IoctlsSetAndShowTheOutput) {
  FakeLeds leds;
  ASSERT_TRUE(leds.open());
  EXPECT_EQ(*leds.ioctl("set", "1 0.25 7"), "1 0.25 1");
  EXPECT_EQ(*leds.ioctl("output"), "1 0.25 1");
  EXPECT_EQ(leds.ioctl("set", "1 x 0").error(), "column 3: expected a number");
  EXPECT_FALSE(leds.ioctl("set", "1 nan 0"));
  EXPECT_EQ(*leds.ioctl("output"), "1 0.25 1");
  EXPECT_EQ(*leds.ioctl("channels"), "red [0, 1] -\ngreen [0, 1] -\nblue [0, 1] -\n");
}

// Sends each of `script`'s commands on its ticks.
class Commander : public os::Task {
 public:
  explicit Commander(std::vector<std::vector<float>> script) : script_(std::move(script)) {}

 protected:
  void on_tick() override {
    if (next_ < script_.size()) send(kDataPort, script_[next_++]);
  }

 private:
  std::vector<std::vector<float>> script_;
  std::size_t next_ = 0;
};

TEST(ActuatorSinkTask, AppliesEveryMessageAndCountsWhatItRefuses) {
  kernel::VirtualTimeExecutor ex;
  os::Node node(ex, {"bot"});
  auto leds = std::make_shared<FakeLeds>();
  auto t = std::make_unique<ActuatorSinkTask>(leds);
  ActuatorSinkTask* sink = t.get();
  auto sink_id = *node.create("leds", std::move(t));
  auto cmd = *node.create("cmd",
                          std::make_unique<Commander>(std::vector<std::vector<float>>{
                              {1, 0, 0}, {0.5f, kNaN, 0}, {0, 3, 0}, {1, 1}, {0, 0, 1}}),
                          {.period = 10ms, .autostart = false});
  ASSERT_TRUE(node.hook(cmd, sink_id, {.policy = os::QueuePolicy::kRefuse}));
  ASSERT_TRUE(node.start(cmd));
  ex.run_for(20ms);
  EXPECT_EQ(leds->output(), (std::vector<float>{1, 0, 0}));  // the NaN at 20 ms changed nothing
  ex.run_for(30ms);
  EXPECT_EQ(leds->output(), (std::vector<float>{0, 0, 1}));
  ASSERT_EQ(leds->applied.size(), 3u);
  EXPECT_EQ(leds->applied[1], (std::vector<float>{0, 1, 0}));
  os::Message blob;
  blob.payload = io::text_payload("hello");
  ASSERT_TRUE(node.post(sink_id, blob));
  ex.run_for(0ms);
  const ActuatorSinkStats s = sink->stats();
  EXPECT_EQ(s.received, 6u);
  EXPECT_EQ(s.applied, 3u);
  EXPECT_EQ(s.failed, 2u);
  EXPECT_EQ(s.ignored, 1u);
  EXPECT_EQ(leds->stats().rejected, 2u);
  std::size_t warns = 0;
  for (const auto& e : node.log().since(0))
    if (e.level == os::LogLevel::kWarn) ++warns;
  EXPECT_EQ(warns, 2u);  // one refusal (the second falls in the same second), one clamp
}

// Sends a command every tick and notes what the actuator shows right after the send.
class WatchingCommander : public os::Task {
 public:
  explicit WatchingCommander(std::shared_ptr<Actuator> watched) : watched_(std::move(watched)) {}
  std::vector<std::vector<float>> seen;

 protected:
  void on_tick() override {
    const float v = static_cast<float>(seen.size() + 1) / 10;
    send(kDataPort, {v, v, v});
    seen.push_back(watched_->output());
  }

 private:
  std::shared_ptr<Actuator> watched_;
};

TEST(ActuatorSinkTask, UnderVirtualTimeACommandIsAppliedInsideItsSendersSend) {
  kernel::VirtualTimeExecutor ex;
  os::Node node(ex, {"bot"});
  auto leds = std::make_shared<FakeLeds>(DeviceThreads::kOneAtATime);
  auto sink = *node.create("leds", std::make_unique<ActuatorSinkTask>(leds));
  auto c = std::make_unique<WatchingCommander>(leds);
  WatchingCommander* cmd = c.get();
  auto cmd_id = *node.create("cmd", std::move(c), {.period = 10ms, .autostart = false});
  ASSERT_TRUE(node.hook(cmd_id, sink));
  ASSERT_TRUE(node.start(cmd_id));
  ex.run_for(20ms);
  ASSERT_EQ(cmd->seen.size(), 2u);
  EXPECT_EQ(cmd->seen[0], (std::vector<float>(3, 0.1f)));
  EXPECT_EQ(cmd->seen[1], (std::vector<float>(3, 0.2f)));
  EXPECT_EQ(node.info(sink)->traffic.delivered, 2u);
  EXPECT_EQ(node.info(sink)->queue_depth, 0u);
}

TEST(ActuatorSinkTask, NarrowerRangesLimitTheOutput) {
  kernel::VirtualTimeExecutor ex;
  os::Node node(ex, {"bot"});
  auto leds = std::make_shared<FakeLeds>();
  ActuatorSinkTask::Options o;
  o.ranges = *apply_ranges(leds->channels(), "0:0.5");
  auto sink = *node.create("leds", std::make_unique<ActuatorSinkTask>(leds, o));
  ex.run_for(0ms);
  os::Message m;
  m.payload = os::Payload{1, 0.25f, 1};
  ASSERT_TRUE(node.post(sink, m));
  ex.run_for(0ms);
  EXPECT_EQ(leds->output(), (std::vector<float>{0.5f, 0.25f, 0.5f}));
}

}  // namespace
}  // namespace symb::robot
