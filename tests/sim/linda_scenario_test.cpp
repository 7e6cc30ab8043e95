// The Linda controller on the simulated Thymio (scenarios/linda_maze.yaml): a spiking network
// grown from the hand-written genome scenarios/linda/avoider.genome drives 10 minutes of virtual
// time through the maze without touching a wall; the same with rate coding; and the network is
// swapped for a differently grown one while the robot drives, twice: by regrowing the running
// task from another genome (its `genome` parameter) and by replacing the task through the node.
#include <cmath>
#include <cstdio>
#include <mutex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "symb/control/snn/aer.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/sim/scenario_session.hpp"

#include "support/measured.hpp"
#include "support/shipped_scenario.hpp"
#include "support/tsan_skip.hpp"

namespace symb::sim {
namespace {

using namespace std::chrono_literals;

// Measured, 10 minutes, seeds 1-3: 50.9, 50.4, 51.1 m (kMeasuredM), never a contact; seeds 1-6:
// 49.8-51.1 m (the same genome in maze_rooms and maze_spiral, seeds 1-8: 49.8 m or more; one of
// those 16 runs touched a wall, for 11 steps); rate coded (below), seed 1: 53.0 m (kRateCodedM).
// Each run is deterministic (same seed, same run), so each is held to its figure within 5% (2.5 m)
// either way: the seeds spread by 3%, and a controller that drives a twentieth less far fails.
constexpr double kLindaMeasuredM[] = {50.9, 50.4, 51.1};
constexpr double kRateCodedM = 53.0;
constexpr double kLindaMarginM = 2.5;

TaskSpec* task(Scenario& s, const std::string& name) {
  for (TaskSpec& t : s.robots.at(0).tasks)
    if (t.name == name) return &t;
  return nullptr;
}

struct LindaOutcome {
  double distance = 0;
  std::uint64_t contact_steps = 0;
  std::uint64_t steps = 0;
};

LindaOutcome run_linda(const Scenario& scenario, kernel::Duration duration, std::uint64_t seed = 1) {
  kernel::VirtualTimeExecutor executor;
  SessionOptions options;
  options.seed = seed;
  auto session = ScenarioSession::create(scenario, executor, options);
  EXPECT_TRUE(session.ok()) << (session ? "" : session.error());
  if (!session) return {};
  (*session)->start();
  executor.run_for(duration);
  (*session)->stop();
  const RobotState s = (*session)->world().state(0);
  return {s.distance, s.contact_steps, (*session)->world().steps()};
}

TEST(LindaScenario, TenMinutesInTheMazeWithoutTouchingAWall) {
  SYMB_SKIP_UNDER_TSAN();
  const Scenario sc = test::load_shipped("linda_maze.yaml");
  for (std::uint64_t seed : {1, 2, 3}) {
    SCOPED_TRACE(seed);
    const LindaOutcome o = run_linda(sc, 10min, seed);
    std::printf("linda maze, seed %llu: %.1f m, %llu contact steps\n", static_cast<unsigned long long>(seed),
                o.distance / 100, static_cast<unsigned long long>(o.contact_steps));
    EXPECT_EQ(o.steps, 20000u);
    EXPECT_EQ(o.contact_steps, 0u);
    EXPECT_TRUE(testing::near_measured(o.distance / 100, kLindaMeasuredM[seed - 1], kLindaMarginM));
  }
}

// Rate coding: each IR value becomes a Bernoulli spike train (1000 Hz at full scale, one event per
// ms at most), each event a pulse of 200 that makes its sensor neuron fire. The same network then
// drives as far, but the noise makes it graze a wall now and then: measured (10 minutes, seeds 1
// and 2) 52.6-53.0 m and 2-3 brief contacts (12-15 steps of 20,000).
TEST(LindaScenario, RateCodedSensorsAlsoDriveTheMaze) {
  Scenario sc = test::load_shipped("linda_maze.yaml");
  auto set = [&sc](const std::string& task_name, const std::string& param, const std::string& value) {
    TaskSpec* t = task(sc, task_name);
    ASSERT_NE(t, nullptr);
    for (os::ParamAssignment& a : t->params)
      if (a.name == param) {
        a.value = value;
        return;
      }
    t->params.push_back({param, value, 1});
    t->param_where.push_back(t->param_where.empty() ? SourceLocation{} : t->param_where.back());
  };
  set("encoder", "coding", "rate");
  set("encoder", "max_rate", "1000");
  set("controller", "pulse", "200");
  const LindaOutcome o = run_linda(sc, 10min);
  std::printf("linda maze, rate coded: %.1f m, %llu contact steps\n", o.distance / 100,
              static_cast<unsigned long long>(o.contact_steps));
  EXPECT_LT(o.contact_steps, 30u);  // measured 12 (seed 2: 15): twice that at most
  EXPECT_TRUE(testing::near_measured(o.distance / 100, kRateCodedM, kLindaMarginM));
}

// Counts the output-channel spikes it is sent, and their last timestamp.
class SpikeCounter : public os::Task {
 public:
  std::uint64_t count() const {
    std::lock_guard lock(mu_);
    return count_;
  }

 protected:
  void on_message(const os::Message& m) override {
    if (const auto* p = control::snn::aer_of(m)) {
      std::lock_guard lock(mu_);
      count_ += p->events.size();
    }
  }

 private:
  mutable std::mutex mu_;
  std::uint64_t count_ = 0;
};

TEST(LindaSwap, NetworkRegrownFromAnotherGenomeAndReplacedWhileTheRobotDrives) {
  kernel::VirtualTimeExecutor executor;
  auto s = ScenarioSession::create(test::load_shipped("linda_maze.yaml"), executor);
  ASSERT_TRUE(s.ok()) << (s ? "" : s.error());
  ScenarioSession& session = **s;
  os::Node& node = session.robot(0).node();
  const auto encoder = node.find("encoder"), controller = node.find("controller"), decoder = node.find("decoder");
  ASSERT_TRUE(encoder && controller && decoder);
  std::vector<RobotState> states;
  session.runner().add_observer([&](const StepRecord& r) { states.push_back(r.robots[0].state); });
  session.start();
  executor.run_for(30s);
  const double d0 = session.world().state(0).distance;
  ASSERT_GT(d0, 100.0);

  // 1. Regrow the running task from a differently grown genome (avoider_slow.genome: another
  // developmental program, a smaller tonic current in the motor neurons).
  const std::size_t swap1 = states.size();
  ASSERT_TRUE(node.set_parameter(*controller, "genome", "linda/avoider_slow.genome").ok());
  executor.run_for(30s);
  const double d1 = session.world().state(0).distance;
  EXPECT_GT(d1 - d0, 100.0);

  // 2. Replace the task: create another linda task, wire it, remove the old one.
  auto params = os::parse_param_assignments("genome=linda/avoider.genome module=1");
  ASSERT_TRUE(params.ok());
  auto fresh = node.create("linda", "controller2", *params);
  ASSERT_TRUE(fresh.ok()) << (fresh ? "" : fresh.error());
  auto counter_task = std::make_unique<SpikeCounter>();
  SpikeCounter* counter = counter_task.get();
  const auto counter_id = *node.create("counter", std::move(counter_task), {.queue_capacity = 64});
  ASSERT_TRUE(node.hook(*encoder, *fresh).ok());
  os::HookOptions port1;
  port1.port = 1;
  ASSERT_TRUE(node.hook(*fresh, *decoder, port1).ok());
  ASSERT_TRUE(node.hook(*fresh, counter_id, port1).ok());
  ASSERT_TRUE(node.remove(*controller).ok());
  const std::size_t swap2 = states.size();
  executor.run_for(30s);
  session.stop();
  const double d2 = session.world().state(0).distance;
  EXPECT_GT(d2 - d1, 100.0);
  EXPECT_GT(counter->count(), 1000u) << "the new network's motor neurons fire";
  EXPECT_EQ(session.world().state(0).contact_steps, 0u);
  // The robot never stood still for long around either swap: no step without wheel speeds for
  // more than a decoder window.
  for (std::size_t start : {swap1, swap2}) {
    std::size_t still = 0;
    for (std::size_t i = start; i < std::min(states.size(), start + 200); ++i) {
      still = (states[i].left_speed == 0 && states[i].right_speed == 0) ? still + 1 : 0;
      ASSERT_LT(still, 10u) << "step " << i - start << " after a swap";
    }
  }
  const os::TaskInfo dec = *node.info(*decoder);
  EXPECT_EQ(dec.traffic.attempted, dec.traffic.delivered + dec.traffic.dropped() + dec.queue_depth);
  EXPECT_EQ(dec.traffic.dropped(), 0u);
}

}  // namespace
}  // namespace symb::sim
