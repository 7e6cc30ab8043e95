// The maze demo end to end, in-process: scenario file -> Enki world -> per robot a node whose
// task graph is ir (sensor task) -> controller (MDL2e) -> wheels (actuator task), on the
// virtual-time executor. Behaviour is measured over 10 minutes of virtual time in every shipped
// maze; runtime reconfiguration goes through the command shell, as a person would do it.
#include "symb/sim/scenario_session.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "symb/evo/embryogenesis/embryogenesis.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/shell/shell.hpp"

#include "support/measured.hpp"
#include "support/shipped_scenario.hpp"

namespace symb::sim {
namespace {

using namespace std::chrono_literals;
namespace fs = std::filesystem;

// How far the demo drives in 10 minutes (the program drives at forward(300) = 10 cm/s, so 60 m if
// it never turned). Measured with each maze's own seed: 51.4 m (maze), 55.1 m (maze_rooms), 55.6 m
// (maze_spiral); seeds 1 to 4: 50 to 56 m. The runs are deterministic (same seed, same run), so
// each is held to its figure within 5% (2.6 m) either way: a demo that drives a twentieth less far
// fails.
const std::map<std::string, double> kSessionMeasuredM = {
    {"maze.yaml", 51.4}, {"maze_rooms.yaml", 55.1}, {"maze_spiral.yaml", 55.6}};
constexpr double kSessionMarginM = 2.6;

struct SessionOutcome {
  double distance = 0;
  std::uint64_t contact_steps = 0;
  std::uint64_t steps = 0;
  std::vector<Pose> poses;  // every step
};

SessionOutcome run_session(const Scenario& scenario, kernel::Duration duration) {
  kernel::VirtualTimeExecutor executor;
  auto session = ScenarioSession::create(scenario, executor);
  EXPECT_TRUE(session.ok()) << (session ? "" : session.error());
  if (!session) return {};
  SessionOutcome out;
  (*session)->runner().add_observer([&](const StepRecord& r) { out.poses.push_back(r.robots[0].state.pose); });
  (*session)->start();
  executor.run_for(duration);
  (*session)->stop();
  const RobotState s = (*session)->world().state(0);
  out.distance = s.distance;
  out.contact_steps = s.contact_steps;
  out.steps = (*session)->world().steps();
  return out;
}

std::vector<std::string> shipped_mazes() {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(SYMB_SCENARIO_DIR)) {
    const std::string n = e.path().filename().string();
    if (n.starts_with("maze") && n.ends_with(".yaml")) names.push_back(n);
  }
  std::sort(names.begin(), names.end());
  return names;
}

TEST(MazeDemo, EveryShippedMazeTenMinutesMovingWithoutTouchingAWall) {
  const auto mazes = shipped_mazes();
  ASSERT_GE(mazes.size(), 3u) << "keep several mazes";
  for (const std::string& name : mazes) {
    SCOPED_TRACE(name);
    const Scenario sc = test::load_shipped(name);
    const SessionOutcome o = run_session(sc, 10min);
    std::printf("%s: %.1f m, %llu contact steps\n", name.c_str(), o.distance / 100,
                static_cast<unsigned long long>(o.contact_steps));
    EXPECT_EQ(o.steps, 20000u);  // 600 s at 30 ms
    EXPECT_EQ(o.contact_steps, 0u);
    ASSERT_TRUE(kSessionMeasuredM.contains(name)) << "a new maze: measure it and add its figure here";
    EXPECT_TRUE(testing::near_measured(o.distance / 100, kSessionMeasuredM.at(name), kSessionMarginM));
  }
}

// A scenario hook between two task types whose ports disagree is refused when the session builds
// the robot, naming both ends and both layouts.
TEST(MazeDemo, AHookBetweenIncompatibleLayoutsIsAnError) {
  Scenario s = test::load_shipped("maze.yaml");
  ASSERT_FALSE(s.robots.empty());
  TaskSpec layer;
  layer.name = "layer";
  layer.type = "avoid";
  s.robots[0].tasks.push_back(layer);
  HookSpec hook;
  hook.from = "controller";
  hook.to = "layer";
  s.robots[0].hooks.push_back(hook);
  kernel::VirtualTimeExecutor executor;
  auto session = ScenarioSession::create(s, executor);
  ASSERT_FALSE(session);
  for (const char* part : {"'controller' (mdl2e)", "'layer' (avoid)", "wheel-command", "sensor-vector"})
    EXPECT_NE(session.error().find(part), std::string::npos) << part << " in " << session.error();
}

// The device tasks declare their layouts (sim::device_task_ports): the IR ring's sensor vector
// into the wheels, or the pose into a controller that reads IR, is refused by the scenario's hook.
TEST(MazeDemo, ADeviceHookBetweenIncompatibleLayoutsIsAnError) {
  const std::vector<std::tuple<std::string, std::string, std::vector<const char*>>> cases = {
      {"ir", "wheels", {"'ir' (sensor)", "'wheels' (actuator_sink)", "sensor-vector", "wheel-command"}},
      {"pose", "controller", {"'pose' (sensor)", "'controller' (mdl2e)", "carries pose"}},
  };
  for (const auto& [from, to, parts] : cases) {
    Scenario s = test::load_shipped("maze.yaml");
    ASSERT_FALSE(s.robots.empty());
    HookSpec hook;
    hook.from = from;
    hook.to = to;
    s.robots[0].hooks.push_back(hook);
    kernel::VirtualTimeExecutor executor;
    auto session = ScenarioSession::create(s, executor);
    ASSERT_FALSE(session) << hook.from << " -> " << hook.to;
    for (const char* part : parts)
      EXPECT_NE(session.error().find(part), std::string::npos) << part << " in " << session.error();
  }
}

TEST(MazeDemo, SameSeedSameRunDifferentSeedDifferentRun) {
  Scenario sc = test::load_shipped("maze.yaml");
  const SessionOutcome a = run_session(sc, 60s), b = run_session(sc, 60s);
  ASSERT_EQ(a.poses.size(), b.poses.size());
  for (std::size_t i = 0; i < a.poses.size(); ++i) {
    ASSERT_EQ(a.poses[i].x, b.poses[i].x) << "step " << i;
    ASSERT_EQ(a.poses[i].y, b.poses[i].y) << "step " << i;
    ASSERT_EQ(a.poses[i].theta, b.poses[i].theta) << "step " << i;
  }
  sc.seed += 1;
  const SessionOutcome c = run_session(sc, 60s);
  bool differs = false;
  for (std::size_t i = 0; i < a.poses.size() && !differs; ++i) differs = a.poses[i].x != c.poses[i].x;
  EXPECT_TRUE(differs) << "the seed drives the sensor noise: another seed must give another run";
}

// Share of steps in which the far-right IR sensor has a wall in sight (it reads 0 beyond 14 cm).
double right_wall_in_sight(const Scenario& scenario, kernel::Duration duration) {
  kernel::VirtualTimeExecutor executor;
  auto session = ScenarioSession::create(scenario, executor);
  EXPECT_TRUE(session.ok()) << (session ? "" : session.error());
  if (!session) return 0;
  std::size_t seen = 0, steps = 0;
  (*session)->runner().add_observer([&](const StepRecord& r) {
    ++steps;
    if (r.robots[0].ir[4] > 1000) ++seen;
  });
  (*session)->start();
  executor.run_for(duration);
  (*session)->stop();
  return steps ? static_cast<double>(seen) / steps : 0;
}

TEST(MazeDemo, WallFollowingKeepsAWallOnItsRight) {
  Scenario follower = test::load_shipped("wall_following.yaml");
  const SessionOutcome o = run_session(follower, 5min);
  EXPECT_GT(o.distance, 1500.0) << "it drives along the wall, not on the spot";
  // Following a wall, measured: the wall is in the right sensor's sight 84% of the time; the
  // obstacle avoider in the same box, 1%. (The follower grazes a wall now and then: 7 contacts in
  // 5 minutes, measured, which is why this test does not ask for zero.)
  EXPECT_GT(right_wall_in_sight(follower, 5min), 0.7);
  Scenario avoider = follower;
  for (TaskSpec& t : avoider.robots[0].tasks)
    for (auto& p : t.params)
      if (p.name == "program") p.value = "mdl2e/obstacle_avoidance.mdl2e";
  EXPECT_LT(right_wall_in_sight(avoider, 5min), 0.2);
}

// Runtime reconfiguration through the command shell, on a running robot.
class ShellOnRunningRobot : public ::testing::Test {
 protected:
  void SetUp() override {
    auto s = ScenarioSession::create(test::load_shipped("maze.yaml"), executor_);
    ASSERT_TRUE(s.ok()) << (s ? "" : s.error());
    session_ = std::move(s).value();
    session_->runner().add_observer([this](const StepRecord& r) { speeds_.push_back(r.robots[0].state); });
    session_->start();
    shell_ = std::make_unique<shell::Shell>(session_->robot(0).node());
    executor_.run_for(5s);
  }
  void TearDown() override {
    shell_.reset();
    session_.reset();
  }
  void command(const std::string& line) {
    const auto reply = shell_->execute(line);
    ASSERT_TRUE(reply.ok) << line << ": " << reply.text;
  }
  bool moving(const RobotState& s) const { return s.left_speed != 0 || s.right_speed != 0; }

  kernel::VirtualTimeExecutor executor_;
  std::unique_ptr<ScenarioSession> session_;
  std::unique_ptr<shell::Shell> shell_;
  std::vector<RobotState> speeds_;  // wheel speeds used in each step
};

// The shell and a genome meet the same rule as a scenario file: Node::hook refuses the IR ring's
// sensor vector into the wheels, naming both ends and both layouts, and the robot drives on.
TEST_F(ShellOnRunningRobot, TheIrIntoTheWheelsIsRefusedFromTheShellAndFromAGenome) {
  os::Node& node = session_->robot(0).node();
  const std::size_t hooks = node.hooks().size();
  const auto reply = shell_->execute("hook ir wheels");
  EXPECT_FALSE(reply.ok);
  auto genome = evo::parse_task_graph("hook ir -> wheels\n");
  ASSERT_TRUE(genome.ok()) << genome.error();
  auto developed = evo::develop(*genome, node);
  ASSERT_FALSE(developed.ok());
  EXPECT_EQ(developed.error().rfind("line 1: hook ir -> wheels: ", 0), 0u) << developed.error();
  for (const std::string& error : {reply.text, developed.error()})
    for (const char* part : {"'ir' (sensor)", "'wheels' (actuator_sink)", "sensor-vector", "wheel-command"})
      EXPECT_NE(error.find(part), std::string::npos) << part << " in " << error;
  EXPECT_EQ(node.hooks().size(), hooks);
  executor_.run_for(1s);
  EXPECT_TRUE(moving(speeds_.back()));
}

TEST_F(ShellOnRunningRobot, SuspendingTheControllerStopsTheWheelsWithinTwoPeriodsAndResumeRestarts) {
  ASSERT_TRUE(moving(speeds_.back()));
  command("suspend controller");
  const std::size_t at = speeds_.size();
  executor_.run_for(1s);
  // Steps at + 0 and at + 1 may still use commands sent before the suspension; from the step two
  // control periods after it, the wheels stand still and stay so.
  for (std::size_t i = at + 2; i < speeds_.size(); ++i) ASSERT_FALSE(moving(speeds_[i])) << "step " << i - at;
  const double x = session_->world().state(0).pose.x, y = session_->world().state(0).pose.y;
  command("resume controller");
  executor_.run_for(2s);
  EXPECT_TRUE(moving(speeds_.back()));
  const RobotState now = session_->world().state(0);
  EXPECT_GT(std::hypot(now.pose.x - x, now.pose.y - y), 5.0);
}

TEST_F(ShellOnRunningRobot, ReplacingTheControllerWithAnotherTaskAtRuntime) {
  command("delete controller");
  executor_.run_for(300ms);
  EXPECT_FALSE(moving(speeds_.back())) << "the wheels' watchdog stops a robot whose controller is gone";
  // A wall follower takes over, created by type name and wired with hooks, while the world runs.
  command("create mdl2e follower program=mdl2e/wall_following.mdl2e");
  command("hook ir follower");
  command("hook follower wheels");
  const double before = session_->world().state(0).distance;
  executor_.run_for(30s);
  EXPECT_TRUE(moving(speeds_.back()));
  EXPECT_GT(session_->world().state(0).distance - before, 100.0);
  // No contact assertion here: the wall follower grazes the thin ends of the maze's walls, which
  // lie between its sensors' cones (measured: a few contacts per minute in maze.yaml).
}

}  // namespace
}  // namespace symb::sim
