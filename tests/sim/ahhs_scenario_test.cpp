// The hormone controller (AHHS) in the maze: scenarios/ahhs_obstacle_avoidance.yaml over 10
// minutes of virtual time with its fixed seed, and the same network run as one task per
// compartment (ahhs_compartment + ahhs_mixer), which must drive the robot along the same
// trajectory, step for step.
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/shell/shell.hpp"
#include "symb/sim/scenario_session.hpp"

#include "support/measured.hpp"

namespace symb::sim {
namespace {

using namespace std::chrono_literals;

// Measured with seed 1: 37.7 m in 10 minutes (it patrols the second corridor, turning at both
// ends), no contact (docs/ahhs.md); seeds 2-5: 37.6-39.1 m. The run is deterministic (same seed,
// same run), so it is held to its figure within 5% (1.9 m) either way: the seeds spread by 4%, so a
// change of noise passes, and a controller that drives a twentieth less far fails.
constexpr double kAhhsMeasuredM = 37.7;
constexpr double kAhhsMarginM = 1.9;

std::string read_text(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

struct AhhsOutcome {
  double distance = 0;
  std::uint64_t contact_steps = 0;
  std::uint64_t steps = 0;
  std::vector<Pose> poses;
};

AhhsOutcome run_ahhs(const Scenario& scenario, kernel::Duration duration) {
  kernel::VirtualTimeExecutor executor;
  auto session = ScenarioSession::create(scenario, executor);
  EXPECT_TRUE(session.ok()) << (session ? "" : session.error());
  if (!session) return {};
  AhhsOutcome out;
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

const std::string kFile = std::string(SYMB_SCENARIO_DIR) + "/ahhs_obstacle_avoidance.yaml";

TEST(AhhsScenario, TenMinutesInTheMazeWithoutTouchingAWall) {
  auto sc = load_scenario(kFile);
  ASSERT_TRUE(sc.ok()) << sc.error();
  const AhhsOutcome o = run_ahhs(*sc, 10min);
  EXPECT_EQ(o.steps, 20000u);
  EXPECT_EQ(o.contact_steps, 0u);
  EXPECT_TRUE(testing::near_measured(o.distance / 100, kAhhsMeasuredM, kAhhsMarginM));
  std::cout << "ahhs maze: " << o.distance / 100 << " m in 10 min, " << o.contact_steps << " contact steps\n";
}

// The shipped file with its controller replaced by one task per compartment and a mixer.
std::string compartment_version() {
  std::string text = read_text(kFile);
  const std::string tasks_at = "    tasks:\n";
  const auto from = text.find(tasks_at);
  EXPECT_NE(from, std::string::npos);
  text = text.substr(0, from) + R"(    tasks:
      - {name: left, type: ahhs_compartment, params: {network: ahhs/two_hormone.ahhs, compartment: 0}}
      - {name: right, type: ahhs_compartment, params: {network: ahhs/two_hormone.ahhs, compartment: 1}}
      - {name: mixer, type: ahhs_mixer, params: {actuators: 2, actuator_scale: 300}}
    hooks:
      - {from: ir, to: left, port: 0}
      - {from: ir, to: right, port: 0}
      - {from: left, to: right, port: 1}
      - {from: right, to: left, port: 1}
      - {from: left, to: mixer, port: 2}
      - {from: right, to: mixer, port: 2}
      - mixer -> wheels
)";
  return text;
}

TEST(AhhsScenario, OneTaskPerCompartmentDrivesTheSameTrajectory) {
  auto whole = load_scenario(kFile);
  ASSERT_TRUE(whole.ok()) << whole.error();
  auto split = parse_scenario(compartment_version(), kFile);
  ASSERT_TRUE(split.ok()) << split.error();
  const AhhsOutcome a = run_ahhs(*whole, 2min), b = run_ahhs(*split, 2min);
  ASSERT_EQ(a.poses.size(), 4000u);
  ASSERT_EQ(b.poses.size(), a.poses.size());
  for (std::size_t i = 0; i < a.poses.size(); ++i) {
    ASSERT_EQ(a.poses[i].x, b.poses[i].x) << "step " << i;
    ASSERT_EQ(a.poses[i].y, b.poses[i].y) << "step " << i;
    ASSERT_EQ(a.poses[i].theta, b.poses[i].theta) << "step " << i;
  }
  EXPECT_GT(a.distance, 300.0);
}

// Runtime rewiring through the command shell, as a person would do it: the one-task controller is
// replaced by compartment tasks and a mixer while the world runs, and the robot drives on.
TEST(AhhsScenario, TheShellSplitsTheControllerIntoCompartmentsAtRuntime) {
  auto sc = load_scenario(kFile);
  ASSERT_TRUE(sc.ok()) << sc.error();
  kernel::VirtualTimeExecutor executor;
  auto session = ScenarioSession::create(*sc, executor);
  ASSERT_TRUE(session.ok()) << session.error();
  (*session)->start();
  shell::Shell shell((*session)->robot(0).node());
  executor.run_for(5s);
  for (const char* line :
       {"delete controller", "create ahhs_compartment left network=ahhs/two_hormone.ahhs compartment=0",
        "create ahhs_compartment right network=ahhs/two_hormone.ahhs compartment=1",
        "create ahhs_mixer mixer actuators=2 actuator_scale=300", "hook ir left --port 0", "hook ir right --port 0",
        "hook left right --port 1", "hook right left --port 1", "hook left mixer --port 2", "hook right mixer --port 2",
        "hook mixer wheels"}) {
    const auto reply = shell.execute(line);
    ASSERT_TRUE(reply.ok) << line << ": " << reply.text;
  }
  const auto bad = shell.execute("create ahhs_compartment third network=ahhs/two_hormone.ahhs compartment=2");
  EXPECT_FALSE(bad.ok);
  EXPECT_NE(bad.text.find("compartment 2 is not in the network"), std::string::npos) << bad.text;
  const double before = (*session)->world().state(0).distance;
  executor.run_for(60s);
  const RobotState now = (*session)->world().state(0);
  EXPECT_GT(now.distance - before, 300.0) << "it drives on under the compartment tasks";
  EXPECT_EQ(now.contact_steps, 0u);
  (*session)->stop();
}

}  // namespace
}  // namespace symb::sim
