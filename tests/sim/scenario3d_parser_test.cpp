// 3D scenario files (world: {kind: mujoco}) and the events of both worlds: what parse_scenario
// reads (module kinds through an injected reader, starts in the world's units, modules placed by
// their docks), and every located error of a malformed one: a kind file missing or broken (the
// error in the kind file's own place), docked pairs naming what does not exist or whose faces
// cannot meet, organisms with no start or two, overlapping modules, remote hooks to nothing or
// without a bus, events at bad times, for missing robots or with lines the shell cannot read,
// and keys of one world in the other. A 2D run's event acts on its robot's node.
#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/sim/scenario.hpp"
#include "symb/sim/scenario_session.hpp"

namespace symb::sim {
namespace {

using namespace std::chrono_literals;

std::string s3d_read(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Kind files served from memory: the shipped cube and long, a broken one, and a cube whose front
// connector sits 3 cm above its centre.
ScenarioParseOptions s3d_kinds() {
  static const std::map<std::string, std::string, std::less<>> files = [] {
    std::map<std::string, std::string, std::less<>> f;
    const std::string cube = s3d_read(std::string(SYMB_SCENARIO_DIR) + "/modules/cube.yaml");
    f["modules/cube.yaml"] = cube;
    f["modules/long.yaml"] = s3d_read(std::string(SYMB_SCENARIO_DIR) + "/modules/long.yaml");
    std::string broken = cube;
    broken.replace(broken.find("mass: 0.40"), 10, "mass: -1");
    f["modules/broken.yaml"] = broken;
    std::string high = cube;
    high.replace(high.find("position: [0.05, 0, 0]"), 22, "position: [0.05, 0, 0.03]");
    f["modules/high.yaml"] = high;
    return f;
  }();
  ScenarioParseOptions o;
  o.read_module_kind = [](std::string_view name) -> kernel::Result<std::string> {
    auto it = files.find(name);
    if (it == files.end()) return kernel::Error{"no such file"};
    return it->second;
  };
  return o;
}

Scenario s3d_ok(const std::string& yaml) {
  auto sc = parse_scenario(yaml, "t.yaml", s3d_kinds());
  EXPECT_TRUE(sc.ok()) << sc.error() << "\n--- in ---\n" << yaml;
  return sc.ok() ? std::move(sc).value() : Scenario{};
}

// The error starts with `where` and contains `what`.
void s3d_error(const std::string& yaml, const std::string& where, const std::string& what) {
  auto sc = parse_scenario(yaml, "t.yaml", s3d_kinds());
  ASSERT_FALSE(sc.ok()) << "accepted:\n" << yaml;
  EXPECT_EQ(sc.error().substr(0, where.size()), where) << sc.error();
  EXPECT_NE(sc.error().find(what), std::string::npos) << "'" << what << "' not in: " << sc.error();
}

// A chain of three cubes: lines 1 name, 2 world, 3 kind, 4 docked, 5 robots, 6 the entry, 7 its
// module, 8 its start.
const std::string kChain3 =
    "name: t\n"
    "world:\n"
    "  kind: mujoco\n"
    "  docked: [[m0.back, m1.front], [m1.back, m2.front]]\n"
    "robots:\n"
    "  - name: m\n"
    "    count: 3\n"
    "    module: modules/cube.yaml\n"
    "    start: {x: 50, y: 20, heading: 90}\n";

TEST(Scenario3d, ModulesArePlacedByTheirDocksInTheWorldsUnits) {
  const Scenario sc = s3d_ok(kChain3);
  ASSERT_EQ(sc.world_kind, WorldKind::kMujoco);
  ASSERT_EQ(sc.robots.size(), 3u);
  EXPECT_EQ(sc.robots[0].module, "modules/cube.yaml");
  EXPECT_EQ(sc.robots[0].module_kind.name, "cube");
  // m0 where the file says (cm, degrees -> m, rad); facing +y, so the others follow along -y.
  for (std::size_t i = 0; i < 3; ++i) {
    SCOPED_TRACE(i);
    EXPECT_NEAR(sc.robots[i].module_start.x, 0.50, 1e-12);
    EXPECT_NEAR(sc.robots[i].module_start.y, 0.20 - 0.10 * static_cast<double>(i), 1e-12);
    EXPECT_NEAR(sc.robots[i].module_start.yaw, std::numbers::pi / 2, 1e-12);
    EXPECT_NEAR(sc.robots[i].start.y, 20.0 - 10.0 * static_cast<double>(i), 1e-9);  // cm, as in 2D
  }
  ASSERT_EQ(sc.organism.docked.size(), 2u);
  EXPECT_EQ(sc.organism.docked[1].a, 1u);
  EXPECT_EQ(sc.organism.docked[1].connector_a, "back");
  EXPECT_EQ(sc.organism.docked[1].b, 2u);
  EXPECT_EQ(sc.organism.docked[1].connector_b, "front");
  EXPECT_EQ(sc.organism.docked[1].where.str(), "t.yaml:4:33");
}

TEST(Scenario3d, ASideDockTurnsTheSecondModuleAndDifferentKindsMeetWithinTheTolerance) {
  const Scenario sc = s3d_ok(
      "name: t\n"
      "world: {kind: mujoco, docked: [[a.left, b.back]]}\n"
      "robots:\n"
      "  - {name: a, module: modules/cube.yaml, start: {x: 0, y: 0}}\n"
      "  - {name: b, module: modules/long.yaml}\n");
  // a's left connector (2.5 cm ahead of its centre, on +y) faces +y; b's back must face -y, so b
  // heads +y, its centre 8 cm (half its length) beyond the connector.
  EXPECT_NEAR(sc.robots[1].module_start.yaw, std::numbers::pi / 2, 1e-12);
  EXPECT_NEAR(sc.robots[1].module_start.x, 0.025, 1e-12);
  EXPECT_NEAR(sc.robots[1].module_start.y, 0.05 + 0.08, 1e-12);
}

TEST(Scenario3d, BusAndRemoteHooksAreParsedAndResolved) {
  const Scenario sc = s3d_ok(
      "name: t\n"
      "world:\n"
      "  kind: mujoco\n"
      "  bus: {bandwidth: 500000, latency: 2ms}\n"
      "robots:\n"
      "  - name: a\n"
      "    module: modules/cube.yaml\n"
      "    start: {x: 0, y: 0}\n"
      "    tasks: [{name: osc, type: mdl2e}]\n"
      "    hooks: [{from: osc, to: b/hinge, port: 0, priority: 3}]\n"
      "  - {name: b, module: modules/cube.yaml, start: {x: 40, y: 0}}\n");
  ASSERT_TRUE(sc.organism.bus.has_value());
  EXPECT_EQ(sc.organism.bus->bandwidth, 500000u);
  EXPECT_EQ(sc.organism.bus->latency, 2ms);
  ASSERT_EQ(sc.robots[0].remote_hooks.size(), 1u);
  const RemoteHookSpec& h = sc.robots[0].remote_hooks[0];
  EXPECT_EQ(h.from, "osc");
  EXPECT_EQ(h.to_robot, "b");
  EXPECT_EQ(h.to_index, 1u);
  EXPECT_EQ(h.to, "hinge");
  EXPECT_EQ(h.options.port, 0);
  EXPECT_EQ(h.options.priority, 3);
  EXPECT_EQ(h.to_where.str(), "t.yaml:10:29");
  EXPECT_TRUE(sc.robots[0].hooks.empty());
}

TEST(Scenario3d, EventsAreCheckedAndSortedByTime) {
  const Scenario sc = s3d_ok(kChain3 +
                             "duration: 10s\n"
                             "events:\n"
                             "  - {at: 5s, robot: m2, shell: \"ioctl connector_back latch\"}\n"
                             "  - {at: 1s, robot: m0, shell: tasks}\n"
                             "  - {at: 5s, robot: m1, shell: 'ioctl connector_front state'}\n");
  ASSERT_EQ(sc.events.size(), 3u);
  EXPECT_EQ(sc.events[0].at, 1s);
  EXPECT_EQ(sc.events[0].robot, 0u);
  EXPECT_EQ(sc.events[1].robot, 2u);  // ties keep file order
  EXPECT_EQ(sc.events[2].robot, 1u);
  EXPECT_EQ(sc.events[1].line, "ioctl connector_back latch");
  EXPECT_EQ(sc.events[1].where.str(), "t.yaml:12:5");
}

TEST(Scenario3d, KindFileErrors) {
  std::string missing = kChain3;
  missing.replace(missing.find("modules/cube.yaml"), 17, "modules/none.yaml");
  s3d_error(missing, "t.yaml:8:13: ", "cannot read module kind 'modules/none.yaml'");
  std::string broken = kChain3;
  broken.replace(broken.find("modules/cube.yaml"), 17, "modules/broken.yaml");
  // The kind file's own place first, then where the scenario names it.
  s3d_error(broken, "modules/broken.yaml:9:9: ", "(the module kind named at t.yaml:8:13)");
  std::string none = kChain3;
  none.replace(none.find("    module: modules/cube.yaml\n"), 30, "");
  s3d_error(none, "t.yaml:6:5: ", "a robot needs 'module'");
}

TEST(Scenario3d, DockedPairErrors) {
  auto with = [](const std::string& docked) {
    std::string s = kChain3;
    s.replace(s.find("[[m0.back, m1.front], [m1.back, m2.front]]"), 42, docked);
    return s;
  };
  s3d_error(with("[[m0.back, m9.front], [m1.back, m2.front]]"), "t.yaml:4:22: ", "there is no robot 'm9'");
  s3d_error(with("[[m0.bakc, m1.front], [m1.back, m2.front]]"),
            "t.yaml:4:13: ", "has no connector 'bakc' (did you mean 'back'?)");
  s3d_error(with("[[m0.back, m1.front], [m1.back, m2]]"), "t.yaml:4:43: ", "names no connector");
  s3d_error(with("[[m0.back, m1.front], [m1.back, m0.back]]"), "t.yaml:4:43: ", "'m0.back' is docked twice");
  s3d_error(with("[[m0.back, m0.front], [m1.back, m2.front]]"), "t.yaml:4:12: ", "docked to itself");
  s3d_error(with("[[m0.back, m1.front, m2.front]]"), "t.yaml:4:12: ", "a docked pair is [ROBOT.CONNECTOR");
  // A ring that does not close: m2's back is 30 cm from m0's front.
  s3d_error(with("[[m0.back, m1.front], [m1.back, m2.front], [m2.back, m0.front]]"), "t.yaml:4:33: ",
            "m1.back and m2.front cannot meet: placed by their other docks, their centres are 300 mm apart");
  // Faces that cannot meet in height: the connector 3 cm up.
  s3d_error(
      "name: t\n"
      "world: {kind: mujoco, docked: [[a.back, b.front]]}\n"
      "robots:\n"
      "  - {name: a, module: modules/cube.yaml, start: {x: 0, y: 0}}\n"
      "  - {name: b, module: modules/high.yaml}\n",
      "t.yaml:2:32: ", "a.back and b.front cannot meet: placed face to face, their centres are 30 mm apart");
}

TEST(Scenario3d, StartErrors) {
  std::string second = kChain3 + "    # the others\n";
  second.replace(second.find("    start: {x: 50, y: 20, heading: 90}"), 38,
                 "    start: [{x: 50, y: 20}, {x: 50, y: 60}, {x: 80, y: 80}]");
  s3d_error(second, "t.yaml:9:29: ", "robot 'm1' is placed by docking");
  std::string no_start = kChain3;
  no_start.replace(no_start.find("    start: {x: 50, y: 20, heading: 90}\n"), 39, "");
  s3d_error(no_start, "t.yaml:4:12: ", "the organism of 'm0' has no start");
  s3d_error(
      "name: t\n"
      "world: {kind: mujoco}\n"
      "robots:\n"
      "  - {name: a, module: modules/cube.yaml, start: {x: 0, y: 0}}\n"
      "  - {name: b, module: modules/cube.yaml}\n",
      "t.yaml:5:5: ", "robot 'b' has no start");
  s3d_error(
      "name: t\n"
      "world: {kind: mujoco}\n"
      "robots:\n"
      "  - {name: a, module: modules/cube.yaml, start: {x: 0, y: 0}}\n"
      "  - {name: b, module: modules/cube.yaml, start: {x: 8, y: 3, heading: 45}}\n",
      "t.yaml:5:49: ", "robot 'b' would start inside robot 'a'");
  s3d_error(
      "name: t\n"
      "world: {kind: mujoco}\n"
      "robots:\n"
      "  - {name: a, count: 2, module: modules/cube.yaml, start: random}\n",
      "t.yaml:4:59: ", "no arena to place modules at random");
  s3d_error(
      "name: t\n"
      "world: {kind: mujoco}\n"
      "robots:\n"
      "  - {name: a-1, module: modules/cube.yaml, start: {x: 0, y: 0}}\n",
      "t.yaml:4:12: ", "has a '-'");
}

TEST(Scenario3d, RemoteHookErrors) {
  const std::string head =
      "name: t\n"
      "world:\n"
      "  kind: mujoco\n"
      "  bus: {}\n"
      "robots:\n"
      "  - {name: b, module: modules/long.yaml, start: {x: 40, y: 0}}\n"
      "  - name: a\n"
      "    module: modules/cube.yaml\n"
      "    start: {x: 0, y: 0}\n"
      "    tasks: [{name: osc, type: mdl2e}]\n"
      "    hooks:\n";
  s3d_error(head + "      - {from: osc, to: c/hinge}\n", "t.yaml:12:25: ", "there is no robot 'c'");
  s3d_error(head + "      - {from: osc, to: b/hnige}\n",
            "t.yaml:12:25: ", "robot 'b' has no task 'hnige' (did you mean 'hinge'?)");
  s3d_error(head + "      - {from: osc, to: b/wheels}\n", "t.yaml:12:25: ", "has no wheels");
  s3d_error(head + "      - {from: osc, to: a/hinge}\n", "t.yaml:12:25: ", "is this hook's own robot");
  s3d_error(head + "      - {from: cso, to: b/hinge}\n", "t.yaml:12:9: ", "robot 'a' has no task 'cso'");
  s3d_error(head + "      - osc -> b/hinge\n", "t.yaml:12:16: ", "write that hook in the long form");
  std::string no_bus = head + "      - {from: osc, to: b/hinge}\n";
  no_bus.replace(no_bus.find("  bus: {}\n"), 10, "");
  s3d_error(no_bus, "t.yaml:11:25: ", "this world has none: add world.bus");
  s3d_error(head.substr(0, head.find("robots:")) + "robots: []\n", "t.yaml:5:9: ", "robots is empty");
}

TEST(Scenario3d, BusErrors) {
  const std::string head = "name: t\nworld:\n  kind: mujoco\n";
  const std::string robots = "robots: [{name: a, module: modules/cube.yaml, start: {x: 0, y: 0}}]\n";
  s3d_error(head + "  bus: {bandwidth: 5}\n" + robots, "t.yaml:4:20: ", "bus bandwidth (bit/s) must be an integer in");
  s3d_error(head + "  bus: {latency: 2s}\n" + robots, "t.yaml:4:18: ", "bus latency must be between");
  s3d_error(head + "  bus: {speed: 1}\n" + robots, "t.yaml:4:9: ", "unknown key 'speed' in bus");
  s3d_error(head + "  bus: fast\n" + robots, "t.yaml:4:8: ", "bus is {bandwidth");
}

TEST(Scenario3d, EventErrors) {
  auto with = [](const std::string& event) { return kChain3 + "duration: 10s\nevents:\n  - " + event + "\n"; };
  s3d_error(with("{at: 11s, robot: m0, shell: tasks}"), "t.yaml:12:10: ", "event time 'at' must be between");
  s3d_error(with("{at: soon, robot: m0, shell: tasks}"), "t.yaml:12:10: ", "event time 'at'");
  s3d_error(with("{at: 1s, robot: m7, shell: tasks}"), "t.yaml:12:21: ", "there is no robot 'm7'");
  s3d_error(with("{at: 1s, robot: m0, shell: 'ioctl \"open'}"), "t.yaml:12:32: ", "event shell line:");
  s3d_error(with("{at: 1s, robot: m0, shell: taks}"),
            "t.yaml:12:32: ", "unknown command 'taks' (did you mean 'tasks'?)");
  s3d_error(with("{at: 1s, robot: m0, shell: '# nothing'}"), "t.yaml:12:32: ", "has no command");
  s3d_error(with("{at: 1s, robot: m0}"), "t.yaml:12:5: ", "an event needs 'shell'");
  s3d_error(with("{at: 1s, robot: m0, shell: tasks, when: now}"), "t.yaml:12:39: ", "unknown key 'when'");
}

TEST(Scenario3d, KeysOfOneWorldInTheOther) {
  s3d_error(
      "name: t\nworld: {kind: mujoco, arena: {width: 100, height: 100}}\n"
      "robots: [{name: a, module: modules/cube.yaml, start: {x: 0, y: 0}}]\n",
      "t.yaml:2:30: ", "'arena' belongs to a 2D world");
  s3d_error(
      "name: t\nworld: {kind: mujoco, walls: []}\n"
      "robots: [{name: a, module: modules/cube.yaml, start: {x: 0, y: 0}}]\n",
      "t.yaml:2:30: ", "'walls' belongs to a 2D world");
  s3d_error(
      "name: t\nworld: {kind: mujoco}\n"
      "robots: [{name: a, kind: thymio2, module: modules/cube.yaml, start: {x: 0, y: 0}}]\n",
      "t.yaml:3:26: ", "'kind' names a 2D robot");
  s3d_error(
      "name: t\nworld: {kind: unity}\n"
      "robots: [{name: a, module: modules/cube.yaml, start: {x: 0, y: 0}}]\n",
      "t.yaml:2:15: ", "unknown world kind 'unity'");
  const std::string flat_robot = "robots: [{name: a, start: {x: 50, y: 50}}]\n";
  s3d_error("name: t\nworld: {arena: {width: 100, height: 100}, docked: []}\n" + flat_robot,
            "t.yaml:2:51: ", "'docked' belongs to a 3D world");
  s3d_error("name: t\nworld: {arena: {width: 100, height: 100}, bus: {}}\n" + flat_robot,
            "t.yaml:2:48: ", "'bus' belongs to a 3D world");
  s3d_error(
      "name: t\nworld: {arena: {width: 100, height: 100}}\n"
      "robots: [{name: a, module: modules/cube.yaml, start: {x: 50, y: 50}}]\n",
      "t.yaml:3:28: ", "'module' names a 3D module kind");
  s3d_error(
      "name: t\nworld: {arena: {width: 100, height: 100}}\n"
      "robots:\n  - name: a\n    start: {x: 50, y: 50}\n    tasks: [{name: c, type: mdl2e}]\n"
      "    hooks: [{from: c, to: b/wheels}]\n",
      "t.yaml:7:27: ", "only in a 3D world");
  // A 3D device task's name is taken in a 2D world too, and is no device there.
  s3d_error(
      "name: t\nworld: {arena: {width: 100, height: 100}}\n"
      "robots:\n  - name: a\n    start: {x: 50, y: 50}\n    tasks: [{name: hinge, type: mdl2e}]\n",
      "t.yaml:6:13: ", "task name 'hinge' is taken");
  s3d_error(
      "name: t\nworld: {arena: {width: 100, height: 100}}\n"
      "robots:\n  - name: a\n    start: {x: 50, y: 50}\n    hooks: [ir -> hinge]\n",
      "t.yaml:6:19: ", "robot 'a' has no task 'hinge'");
}

TEST(Scenario3d, A2dEventRunsThroughTheRobotsShellAtItsTime) {
  auto sc = parse_scenario(
      "name: t\n"
      "duration: 2s\n"
      "world: {arena: {width: 100, height: 100}}\n"
      "robots:\n"
      "  - name: r\n"
      "    start: {x: 50, y: 50}\n"
      "    tasks: [{name: controller, type: mdl2e, params: {program: mdl2e/obstacle_avoidance.mdl2e}}]\n"
      "    hooks: [ir -> controller -> wheels]\n"
      "events:\n"
      "  - {at: 500ms, robot: r, shell: suspend controller}\n"
      "  - {at: 700ms, robot: r, shell: ioctl wheels nothing}\n",
      std::string(SYMB_SCENARIO_DIR) + "/t.yaml");
  ASSERT_TRUE(sc.ok()) << sc.error();
  kernel::VirtualTimeExecutor ex;
  auto made = ScenarioSession::create(*sc, ex);
  ASSERT_TRUE(made.ok()) << made.error();
  ScenarioSession& s = **made;
  s.start();
  ex.run_for(400ms);
  os::Node& node = s.robot(0).node();
  EXPECT_EQ(node.info(*node.find("controller"))->state, os::TaskState::kRunning);
  ex.run_for(1s);
  EXPECT_EQ(node.info(*node.find("controller"))->state, os::TaskState::kSuspended);
  EXPECT_EQ(s.events()->done(), 2u);
  EXPECT_EQ(s.events()->failed(), 1u);  // the wheels have no such ioctl; the run went on
  std::vector<os::LogEntry> seen;
  for (const auto& e : node.log().since(0))
    if (e.source == kEventLogSource) seen.push_back(e);
  ASSERT_EQ(seen.size(), 2u);
  EXPECT_EQ(seen[0].time, kernel::Time(500ms));
  EXPECT_EQ(seen[0].level, os::LogLevel::kInfo);
  EXPECT_EQ(seen[1].time, kernel::Time(700ms));
  EXPECT_EQ(seen[1].level, os::LogLevel::kError);
  // The device was found in the shell's table: only the ioctl is unknown.
  EXPECT_NE(seen[1].text.find("device 'wheels' has no ioctl 'nothing'"), std::string::npos) << seen[1].text;
  EXPECT_EQ(s.runner().ticks(), 1400u / 30u);
}

}  // namespace
}  // namespace symb::sim
