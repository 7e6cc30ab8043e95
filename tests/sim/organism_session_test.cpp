// OrganismSession: 3D scenarios run end to end in virtual time. The shipped five-module chain
// starts docked, stays docked and moves forward as one body a measured distance; the same seed
// gives the same final poses bit for bit; events command a module's connectors through its shell
// (a latch between two free modules at runtime, a refused one logged at error level without
// stopping the run); the module's device tasks are its devices', bound by name and typed by
// port; remote hooks are refused with their place until the organism bus exists. The figures
// beside the bounds were measured once with this file (release build).
#include "symb/sim/mujoco/organism_session.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "symb/kernel/thread_executor.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/sim/scenario.hpp"

#include "support/measured.hpp"

namespace symb::sim::mujoco {
namespace {

using namespace std::chrono_literals;

// Scenario text in the scenarios folder's place, so `modules/cube.yaml` and `mdl2e/...` resolve.
Scenario org_parse(const std::string& text) {
  auto sc = parse_scenario(text, std::string(SYMB_SCENARIO_DIR) + "/inline.yaml");
  EXPECT_TRUE(sc.ok()) << sc.error();
  return sc.ok() ? std::move(sc).value() : Scenario{};
}

std::vector<os::LogEntry> org_log(RobotSystem& r, std::string_view source) {
  std::vector<os::LogEntry> out;
  for (const auto& e : r.node().log().since(0))
    if (e.source == source) out.push_back(e);
  return out;
}

struct OrgRun {
  std::vector<Pose3> poses;
  std::vector<std::vector<std::optional<std::pair<std::size_t, std::size_t>>>> docks;
};

OrgRun org_run_chain(kernel::Duration how_long, std::uint64_t seed) {
  auto sc = load_scenario(std::string(SYMB_SCENARIO_DIR) + "/organism_chain.yaml");
  EXPECT_TRUE(sc.ok()) << sc.error();
  kernel::VirtualTimeExecutor ex;
  SessionOptions so;
  so.seed = seed;
  auto made = OrganismSession::create(*sc, ex, so);
  EXPECT_TRUE(made.ok()) << made.error();
  OrgRun run;
  if (!made.ok()) return run;
  OrganismSession& s = **made;
  s.start();
  ex.run_for(how_long);
  EXPECT_EQ(s.error(), "");
  s.runner().with_world([&](MujocoWorld& w) {
    for (std::size_t m = 0; m < w.module_count(); ++m) {
      run.poses.push_back(w.pose(m));
      run.docks.emplace_back();
      for (std::size_t c = 0; c < w.module(m).kind.connectors.size(); ++c)
        run.docks.back().push_back(w.docked_to(m, c));
    }
  });
  return run;
}

TEST(OrganismSession, TheShippedChainStartsDockedStaysDockedAndMovesForwardAsOneBody) {
  auto sc = load_scenario(std::string(SYMB_SCENARIO_DIR) + "/organism_chain.yaml");
  ASSERT_TRUE(sc.ok()) << sc.error();
  ASSERT_EQ(sc->world_kind, WorldKind::kMujoco);
  ASSERT_EQ(sc->robots.size(), 5u);
  ASSERT_EQ(sc->organism.docked.size(), 4u);
  kernel::VirtualTimeExecutor ex;
  auto made = OrganismSession::create(*sc, ex);
  ASSERT_TRUE(made.ok()) << made.error();
  OrganismSession& s = **made;
  // Placed by docking: each module 10 cm behind the one before, facing the same way.
  for (std::size_t i = 0; i < 5; ++i) {
    const Pose3 p = s.world().pose(i);
    EXPECT_NEAR(p.position[0], -0.10 * static_cast<double>(i), 1e-9) << i;
    EXPECT_NEAR(p.position[1], 0.0, 1e-9) << i;
    EXPECT_NEAR(std::remainder(p.yaw(), 2 * std::numbers::pi), 0.0, 1e-9) << i;
  }
  for (std::size_t i = 0; i + 1 < 5; ++i)
    EXPECT_EQ(s.world().docked_to(i, *s.world().find_connector(i, "back")),
              (std::pair<std::size_t, std::size_t>{i + 1, *s.world().find_connector(i + 1, "front")}));
  EXPECT_TRUE(s.robot(0).node().find("hinge").has_value());
  EXPECT_TRUE(s.robot(0).node().find("hinge_state").has_value());
  EXPECT_FALSE(s.robot(0).node().find("connector_front").has_value());  // no hook names it

  s.start();
  ex.run_for(sc->duration);
  ASSERT_EQ(s.error(), "");
  s.runner().with_world([&](MujocoWorld& w) {
    for (std::size_t i = 0; i + 1 < 5; ++i) {
      EXPECT_EQ(w.connector_state(i, *w.find_connector(i, "back")), ConnectorState::kDocked) << i;
      const Pose3 a = w.pose(i), b = w.pose(i + 1);
      // Still one body: neighbours 10 cm apart, centre to centre, within 2 mm.
      EXPECT_NEAR(std::hypot(a.position[0] - b.position[0], a.position[1] - b.position[1]), 0.10, 0.002) << i;
    }
    // 250 of 500 motor units is 7.5 cm/s at the rim; 10 s of it, less the start, drove the head
    // 0.695 m forward (measured) and kept it on its line.
    const Pose3 head = w.pose(0);
    std::printf("organism_chain: the head drove %.3f m along x, %.4f m off its line, in %.0f s\n", head.position[0],
                head.position[1], w.time());
    EXPECT_TRUE(symb::testing::near_measured(head.position[0], 0.695, 0.03));
    EXPECT_LT(std::abs(head.position[1]), 0.02);
  });
  // The events ran through the modules' shells; their replies are in the logs.
  ASSERT_NE(s.events(), nullptr);
  EXPECT_EQ(s.events()->done(), 2u);
  EXPECT_EQ(s.events()->failed(), 0u);
  const auto head_events = org_log(s.robot(0), kEventLogSource);
  ASSERT_EQ(head_events.size(), 1u);
  EXPECT_EQ(head_events[0].level, os::LogLevel::kInfo);
  EXPECT_NE(head_events[0].text.find("ioctl connector_front close"), std::string::npos) << head_events[0].text;
  EXPECT_NE(head_events[0].text.find("closed"), std::string::npos) << head_events[0].text;
  const auto middle_events = org_log(s.robot(2), kEventLogSource);
  ASSERT_EQ(middle_events.size(), 1u);
  EXPECT_EQ(middle_events[0].time, kernel::Time(5s));
  EXPECT_NE(middle_events[0].text.find("docked"), std::string::npos) << middle_events[0].text;
  // The start's latches reached both partners' logs at the first tick.
  EXPECT_FALSE(org_log(s.robot(1), "connector_front").empty());
  EXPECT_FALSE(org_log(s.robot(1), "connector_back").empty());
}

TEST(OrganismSession, TheSameSeedGivesTheSameFinalPosesBitForBit) {
  const OrgRun a = org_run_chain(3s, 7), b = org_run_chain(3s, 7);
  ASSERT_EQ(a.poses.size(), 5u);
  ASSERT_EQ(b.poses.size(), 5u);
  for (std::size_t i = 0; i < 5; ++i) {
    EXPECT_EQ(std::memcmp(a.poses[i].position.data(), b.poses[i].position.data(), sizeof(double) * 3), 0) << i;
    EXPECT_EQ(std::memcmp(a.poses[i].quaternion.data(), b.poses[i].quaternion.data(), sizeof(double) * 4), 0) << i;
  }
  EXPECT_EQ(a.docks, b.docks);
  EXPECT_GT(a.poses[0].position[0], 0.1);  // it moved, so the comparison compares something
}

constexpr const char* kOrgTwoFree = R"(name: two_free
duration: 2s
world: {kind: mujoco}
robots:
  - {name: a, module: modules/cube.yaml, start: {x: 0, y: 0, heading: 0}}
  - {name: b, module: modules/cube.yaml, start: {x: 11, y: 0, heading: 180}}
events:
  - {at: 100ms, robot: a, shell: "ioctl connector_back latch"}
  - {at: 200ms, robot: a, shell: "ioctl connector_front latch"}
  - {at: 300ms, robot: b, shell: "no_such_thing"}
)";

TEST(OrganismSession, EventsLatchTwoFreeModulesAtRuntimeAndARefusalIsLoggedWithoutStoppingTheRun) {
  // The third event's command is checked at parse time, so it is taken out here and given as a
  // line the shell refuses only when it runs (a latch with nothing in front).
  std::string text = kOrgTwoFree;
  text.replace(text.find("no_such_thing"), 13, "ioctl connector_left latch");
  Scenario sc = org_parse(text);
  ASSERT_EQ(sc.events.size(), 3u);
  kernel::VirtualTimeExecutor ex;
  auto made = OrganismSession::create(sc, ex);
  ASSERT_TRUE(made.ok()) << made.error();
  OrganismSession& s = **made;
  s.start();
  ex.run_for(1s);
  EXPECT_EQ(s.events()->done(), 3u);
  EXPECT_EQ(s.events()->failed(), 2u);  // a's back faces nothing; b's left faces nothing
  s.runner().with_world([&](MujocoWorld& w) {
    EXPECT_EQ(w.docked_to(0, *w.find_connector(0, "front")),
              (std::pair<std::size_t, std::size_t>{1, *w.find_connector(1, "front")}));
  });
  const auto a_events = org_log(s.robot(0), kEventLogSource);
  ASSERT_EQ(a_events.size(), 2u);
  EXPECT_EQ(a_events[0].level, os::LogLevel::kError);
  EXPECT_EQ(a_events[0].time, kernel::Time(100ms));
  EXPECT_EQ(a_events[1].level, os::LogLevel::kInfo);
  EXPECT_NE(a_events[1].text.find("docked"), std::string::npos) << a_events[1].text;
  const auto b_events = org_log(s.robot(1), kEventLogSource);
  ASSERT_EQ(b_events.size(), 1u);
  EXPECT_EQ(b_events[0].level, os::LogLevel::kError);
  // The run went on after the refusals: the runner ticked to the end.
  EXPECT_EQ(s.runner().ticks(), 1000u / 30u);
  EXPECT_EQ(s.error(), "");
}

// Under the thread executor the events run on their own thread while the runner steps the world
// on another: the latch goes through the world's lock, and the session stops cleanly.
TEST(OrganismSession, EventsLatchUnderTheThreadExecutorToo) {
  std::string text = kOrgTwoFree;
  text.replace(text.find("  - {at: 300ms, robot: b, shell: \"no_such_thing\"}\n"), 51, "");
  Scenario sc = org_parse(text);
  ASSERT_EQ(sc.events.size(), 2u);
  kernel::ThreadExecutor ex;
  auto made = OrganismSession::create(sc, ex);
  ASSERT_TRUE(made.ok()) << made.error();
  OrganismSession& s = **made;
  s.start();
  const auto give_up = std::chrono::steady_clock::now() + 10s;
  while (s.events()->done() < 2 && std::chrono::steady_clock::now() < give_up) std::this_thread::sleep_for(10ms);
  EXPECT_EQ(s.events()->done(), 2u);
  EXPECT_EQ(s.events()->failed(), 1u);
  bool docked = false;
  s.runner().with_world([&](MujocoWorld& w) { docked = w.connector_state(0, 0) == ConnectorState::kDocked; });
  EXPECT_TRUE(docked);
  s.stop();
}

TEST(OrganismSession, DeviceTasksAreTheModulesDevicesByNameAndTypedByPort) {
  Scenario sc = org_parse(R"(name: devices
world: {kind: mujoco}
robots:
  - name: a
    module: modules/cube.yaml
    start: {x: 0, y: 0}
    tasks:
      - {name: angle, type: sensor, params: {device: hinge_state}}
      - {name: bend, type: actuator_sink, params: {device: hinge}}
    hooks:
      - {from: connector_front, to: bend, enabled: false}
  - name: b
    module: modules/long.yaml
    start: {x: 40, y: 0}
events:
  - {at: 0s, robot: b, shell: "suspend connector_left"}
  - {at: 0s, robot: b, shell: "ioctl connector_right state"}
)");
  kernel::VirtualTimeExecutor ex;
  auto made = OrganismSession::create(sc, ex);
  ASSERT_TRUE(made.ok()) << made.error();
  OrganismSession& s = **made;
  os::Node& a = s.robot(0).node();
  for (const char* t : {"ir", "hinge_state", "hinge", "wheels", "connector_front", "angle", "bend"})
    EXPECT_TRUE(a.find(t).has_value()) << t;
  EXPECT_FALSE(a.find("connector_back").has_value());
  // The long kind has no wheels, so no wheels task.
  EXPECT_TRUE(s.robot(1).node().find("hinge").has_value());
  EXPECT_FALSE(s.robot(1).node().find("wheels").has_value());
  // An event that names a connector's task gets it made; an ioctl names the device, not a task.
  EXPECT_TRUE(s.robot(1).node().find("connector_left").has_value());
  EXPECT_FALSE(s.robot(1).node().find("connector_right").has_value());
  // A wheel command cannot be hooked into the hinge: the ports' layouts differ.
  Scenario bad = org_parse(R"(name: bad_port
world: {kind: mujoco}
robots:
  - name: a
    module: modules/cube.yaml
    start: {x: 0, y: 0}
    tasks:
      - {name: controller, type: mdl2e, params: {program: mdl2e/organism_forward.mdl2e}}
    hooks:
      - controller -> hinge
)");
  auto refused = OrganismSession::create(bad, ex);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().find("inline.yaml:10:9: hook"), std::string::npos) << refused.error();
}

TEST(OrganismSession, HooksBetweenModulesRideTheBusAndABadOneIsAnErrorAtItsPlace) {
  // b has no controller of its own: a's drives both sets of wheels, b's over the bus.
  const std::string text = R"(name: remote
duration: 2s
world:
  kind: mujoco
  bus: {bandwidth: 1000000, latency: 1ms}
  docked: [[a.back, b.front]]
robots:
  - name: a
    module: modules/cube.yaml
    start: {x: 0, y: 0}
    tasks:
      - {name: controller, type: mdl2e, params: {program: mdl2e/organism_forward.mdl2e}}
    hooks:
      - controller -> wheels
      - {from: controller, to: b/wheels}
  - name: b
    module: modules/cube.yaml
)";
  Scenario sc = org_parse(text);
  ASSERT_EQ(sc.robots[0].remote_hooks.size(), 1u);
  kernel::VirtualTimeExecutor ex;
  auto made = OrganismSession::create(sc, ex);
  ASSERT_TRUE(made.ok()) << made.error();
  OrganismSession& session = **made;
  ASSERT_NE(session.bus(), nullptr);
  const Pose3 b0 = session.world().pose(1);
  session.start();
  ex.run_for(sc.duration);
  const auto hooks = session.bus()->hooks();
  ASSERT_EQ(hooks.size(), 1u);
  EXPECT_EQ(hooks[0].sender, "a/controller");
  EXPECT_EQ(hooks[0].receiver, "b/wheels");
  EXPECT_TRUE(hooks[0].books.closes());
  EXPECT_GE(hooks[0].books.delivered, 60u);  // a command every 30 ms for 2 s
  EXPECT_EQ(hooks[0].books.dropped(), 0u);
  double moved = 0;
  session.runner().with_world([&](MujocoWorld& w) { moved = w.pose(1).position[0] - b0.position[0]; });
  EXPECT_GT(moved, 0.1);

  // A hook to a task the other module does not have is an error at its `to`.
  std::string ghost = text;
  ghost.replace(ghost.find("to: b/wheels}"), 13, "to: b/ghost}");
  auto parsed = parse_scenario(ghost, std::string(SYMB_SCENARIO_DIR) + "/inline.yaml");
  ASSERT_FALSE(parsed.ok());
  EXPECT_NE(parsed.error().find("inline.yaml:15:32: robot 'b' has no task 'ghost'"), std::string::npos)
      << parsed.error();
}

TEST(OrganismSession, EachSessionTakesOnlyItsOwnKindOfWorld) {
  auto flat = load_scenario(std::string(SYMB_SCENARIO_DIR) + "/maze.yaml");
  ASSERT_TRUE(flat.ok()) << flat.error();
  kernel::VirtualTimeExecutor ex;
  auto a = OrganismSession::create(*flat, ex);
  ASSERT_FALSE(a.ok());
  EXPECT_NE(a.error().find("2D world"), std::string::npos) << a.error();
  auto chain = load_scenario(std::string(SYMB_SCENARIO_DIR) + "/organism_chain.yaml");
  ASSERT_TRUE(chain.ok()) << chain.error();
  auto b = ScenarioSession::create(*chain, ex);
  ASSERT_FALSE(b.ok());
  EXPECT_NE(b.error().find("3D world"), std::string::npos) << b.error();
}

}  // namespace
}  // namespace symb::sim::mujoco

namespace symb::sim::mujoco {
namespace {

TEST(OrganismSession, WorldBatteryGivesEveryModuleABatteryThatItsTasksAndShellsReach) {
  Scenario sc = org_parse(R"(name: powered
duration: 3s
world:
  kind: mujoco
  battery: {capacity: 40, share: true}
  docked: [[a.back, b.front]]
robots:
  - name: a
    module: modules/cube.yaml
    start: {x: 0, y: 0}
    tasks:
      - {name: controller, type: mdl2e, params: {program: mdl2e/organism_forward.mdl2e}}
      - {name: power, type: sensor, params: {device: battery}}
    hooks:
      - controller -> wheels
  - name: b
    module: modules/cube.yaml
events:
  - {at: 2s, robot: b, shell: "ioctl battery state"}
)");
  ASSERT_TRUE(sc.organism.battery.has_value());
  kernel::VirtualTimeExecutor ex;
  auto made = OrganismSession::create(sc, ex);
  ASSERT_TRUE(made.ok()) << made.error();
  OrganismSession& s = **made;
  ASSERT_NE(s.batteries(), nullptr);
  s.start();
  ex.run_for(sc.duration);
  // a drives and b idles, but they share, so they hold the same charge: together they lost more
  // than their idle draw (2 x 0.5 W for 3 s) by a's driving.
  const double ea = s.batteries()->energy(0), eb = s.batteries()->energy(1);
  EXPECT_NEAR(ea, eb, 1e-6);
  EXPECT_LT(ea + eb, 80 - 3.0 - 0.5);
  EXPECT_TRUE(s.batteries()->sharing(1));
  const auto events = org_log(s.robot(1), "event");
  ASSERT_EQ(events.size(), 1u);
  EXPECT_NE(events[0].text.find("ioctl battery state: "), std::string::npos) << events[0].text;
  EXPECT_NE(s.robot(0).node().find("power"), std::nullopt);

  auto bad = parse_scenario("name: x\nworld:\n  kind: mujoco\n  battery: {capacity: 0}\nrobots: []\n", "b.yaml");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().find("b.yaml:4:23: battery capacity (J)"), std::string::npos) << bad.error();
  auto flat = parse_scenario(
      "name: x\nworld:\n  arena: {width: 100, height: 100}\n  battery: {capacity: 10}\nrobots: []\n", "f.yaml");
  ASSERT_FALSE(flat.ok());
  EXPECT_NE(flat.error().find("f.yaml:4:12: 'battery' belongs to a 3D world"), std::string::npos) << flat.error();
}

}  // namespace
}  // namespace symb::sim::mujoco
