// The behaviour family's shipped scenarios end to end, in process, over 10 minutes of virtual time
// with fixed seeds: the subsumption robot (wander, avoid, stop_in_zone) ends up stopped inside the
// target zone and stays there; the motor-schema robot (avoid_obstacle, move_to_goal, stay_on_path,
// noise, schema_sum) reaches the goal at the far end of the serpentine maze. Neither touches a wall.
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/shell/shell.hpp"
#include "symb/sim/scenario_session.hpp"

#include "support/shipped_scenario.hpp"

namespace symb::sim {
namespace {

using namespace std::chrono_literals;

struct BehaviourOutcome {
  std::vector<Pose> poses;  // every step (30 ms)
  std::uint64_t contact_steps = 0;
  std::vector<float> last_probe;  // the last ("active") sample of the probed task
};

BehaviourOutcome run_behaviour(const Scenario& scenario, std::uint64_t seed, const std::string& probed_task = "") {
  kernel::VirtualTimeExecutor executor;
  SessionOptions options;
  options.seed = seed;
  auto session = ScenarioSession::create(scenario, executor, options);
  EXPECT_TRUE(session.ok()) << (session ? "" : session.error());
  if (!session) return {};
  BehaviourOutcome out;
  (*session)->runner().add_observer([&](const StepRecord& r) { out.poses.push_back(r.robots[0].state.pose); });
  if (!probed_task.empty())
    (*session)->robot(0).node().set_probe_sink([&](const os::ProbeSample& s) {
      if (s.task == probed_task && s.channel == "active") out.last_probe.assign(s.values.begin(), s.values.end());
    });
  (*session)->start();
  executor.run_for(10min);
  (*session)->stop();
  out.contact_steps = (*session)->world().state(0).contact_steps;
  return out;
}

TEST(SubsumptionScenario, TheRobotStopsInTheTargetZoneAndStaysThere) {
  const Scenario sc = test::load_shipped("subsumption.yaml");
  ASSERT_EQ(sc.world.zones.size(), 1u);
  const ZoneSpec& target = sc.world.zones[0];
  for (std::uint64_t seed : {1, 2, 3}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const BehaviourOutcome o = run_behaviour(sc, seed, "stop");
    ASSERT_EQ(o.poses.size(), 20000u);
    // The first step from which the robot's centre never leaves the zone again.
    std::size_t settled = o.poses.size();
    while (settled > 0 && target.contains(o.poses[settled - 1].x, o.poses[settled - 1].y)) --settled;
    ASSERT_LT(settled, o.poses.size()) << "not in the zone at the end";
    EXPECT_LT(settled, 15000u) << "arrived only after 7.5 minutes";
    // Once stopped it stays: from 2 s after arriving to the end, it moves less than 1 mm.
    const Pose& at = o.poses[std::min(settled + 67, o.poses.size() - 1)];
    for (std::size_t k = settled + 67; k < o.poses.size(); ++k)
      ASSERT_LT(std::hypot(o.poses[k].x - at.x, o.poses[k].y - at.y), 0.1) << "moved at step " << k;
    EXPECT_EQ(o.last_probe, std::vector<float>{1.0f});  // the stop layer is the active one
    EXPECT_EQ(o.contact_steps, 0u);
  }
}

// Dynamic subsumption through the command shell, as a person would do it: the stop layer is
// deleted at the start, so the robot crosses the target zone and wanders on; once it has left the
// zone a new stop layer is created and hooked in above the others, and the robot then stops in it.
TEST(SubsumptionScenario, AStopLayerAddedThroughTheShellAtRuntimeTakesOver) {
  const Scenario sc = test::load_shipped("subsumption.yaml");
  const ZoneSpec& target = sc.world.zones.at(0);
  kernel::VirtualTimeExecutor executor;
  auto session = ScenarioSession::create(sc, executor);
  ASSERT_TRUE(session.ok()) << session.error();
  std::vector<Pose> poses;
  (*session)->runner().add_observer([&](const StepRecord& r) { poses.push_back(r.robots[0].state.pose); });
  shell::Shell sh((*session)->robot(0).node());
  const auto exec = [&](std::string_view line) {
    const shell::Reply r = sh.execute(line);
    EXPECT_TRUE(r.ok) << line << ": " << r.text;
  };
  exec("delete stop");
  (*session)->start();
  // Without the stop layer: on until the robot has crossed the zone and left it again.
  bool crossed = false;
  for (int second = 0; second < 600 && !(crossed && !target.contains(poses.back().x, poses.back().y)); ++second) {
    executor.run_for(1s);
    for (std::size_t k = poses.size() >= 34 ? poses.size() - 34 : 0; k < poses.size(); ++k)
      crossed = crossed || target.contains(poses[k].x, poses[k].y);
  }
  ASSERT_TRUE(crossed) << "never reached the zone in 10 minutes";
  ASSERT_FALSE(target.contains(poses.back().x, poses.back().y));
  const Pose before = poses.back();
  executor.run_for(1s);
  EXPECT_GT(std::hypot(poses.back().x - before.x, poses.back().y - before.y), 3.0) << "still wandering";

  exec("create stop_in_zone stop2 after=1500ms");
  exec("hook ground stop2");
  exec("hook stop2 wheels --priority 2 --suppress 100ms");
  executor.run_for(10min);
  (*session)->stop();
  const Pose end = poses.back();
  EXPECT_TRUE(target.contains(end.x, end.y)) << end.x << ", " << end.y;
  const Pose& earlier = poses[poses.size() - 1 - 200];  // 6 s before the end
  EXPECT_LT(std::hypot(end.x - earlier.x, end.y - earlier.y), 0.1);
  EXPECT_EQ((*session)->world().state(0).contact_steps, 0u);
}

TEST(MotorSchemaScenario, TheRobotReachesTheGoalAtTheFarEndOfTheMaze) {
  const Scenario sc = test::load_shipped("motor_schemas.yaml");
  constexpr double kGoalX = 175, kGoalY = 25, kWithin = 15;
  for (std::uint64_t seed : {1, 2, 3}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const BehaviourOutcome o = run_behaviour(sc, seed);
    ASSERT_EQ(o.poses.size(), 20000u);
    std::optional<std::size_t> reached;
    for (std::size_t k = 0; k < o.poses.size() && !reached; ++k)
      if (std::hypot(o.poses[k].x - kGoalX, o.poses[k].y - kGoalY) <= kWithin) reached = k;
    ASSERT_TRUE(reached.has_value());
    EXPECT_LT(*reached, 4000u) << "took more than 2 minutes";  // measured: about 55 s for seeds 1 to 6
    const Pose& end = o.poses.back();
    EXPECT_LT(std::hypot(end.x - kGoalX, end.y - kGoalY), 6.0);  // and it stays there
    EXPECT_EQ(o.contact_steps, 0u);
  }
}

}  // namespace
}  // namespace symb::sim
