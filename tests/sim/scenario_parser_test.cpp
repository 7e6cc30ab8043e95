// Scenario files: the shipped ones parse and make sense (the mazes' corridors are wide enough to
// turn in), every field reaches the Scenario, `count` expands, and each kind of mistake is
// reported at the line and column of the value that caused it.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "symb/sim/robot_system.hpp"
#include "symb/sim/scenario.hpp"

#include "support/small_stack.hpp"

namespace symb::sim {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

const std::string kDir = SYMB_SCENARIO_DIR;

std::vector<std::string> shipped() {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(kDir))
    if (e.path().extension() == ".yaml") out.push_back(e.path().string());
  std::sort(out.begin(), out.end());
  return out;
}

Scenario parse_ok(const std::string& yaml) {
  auto sc = parse_scenario(yaml, "t.yaml");
  EXPECT_TRUE(sc.ok()) << sc.error() << "\n--- in ---\n" << yaml;
  return sc.ok() ? *sc : Scenario{};
}

// The error must start with `where` ("t.yaml:LINE:COLUMN: ") and contain `what`.
void expect_error(const std::string& yaml, const std::string& where, const std::string& what) {
  auto sc = parse_scenario(yaml, "t.yaml");
  ASSERT_FALSE(sc.ok()) << "accepted:\n" << yaml;
  EXPECT_EQ(sc.error().substr(0, where.size()), where) << sc.error();
  EXPECT_NE(sc.error().find(what), std::string::npos) << "'" << what << "' not in: " << sc.error();
}

// A small valid scenario; tests append robots or replace lines. Lines:
// 1 name, 2 world, 3 arena, 4 walls, 5 the wall, 6 robots, 7 "- name: r", 8 start.
const std::string kHead =
    "name: t\n"
    "world:\n"
    "  arena: {width: 200, height: 100}\n"
    "  walls:\n"
    "    - [100, 0, 100, 60]\n"
    "robots:\n";
const std::string kRobot =
    "  - name: r\n"
    "    start: {x: 50, y: 50}\n";

// Segment-to-segment distance (0 when they cross).
double segments_distance(const WallSpec& a, const WallSpec& b) {
  auto point_seg = [](double x, double y, const WallSpec& s) {
    const double dx = s.x2 - s.x1, dy = s.y2 - s.y1;
    double t = ((x - s.x1) * dx + (y - s.y1) * dy) / (dx * dx + dy * dy);
    t = std::clamp(t, 0.0, 1.0);
    return std::hypot(x - (s.x1 + t * dx), y - (s.y1 + t * dy));
  };
  auto cross = [](double ax, double ay, double bx, double by, double cx, double cy) {
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
  };
  const double d1 = cross(a.x1, a.y1, a.x2, a.y2, b.x1, b.y1), d2 = cross(a.x1, a.y1, a.x2, a.y2, b.x2, b.y2);
  const double d3 = cross(b.x1, b.y1, b.x2, b.y2, a.x1, a.y1), d4 = cross(b.x1, b.y1, b.x2, b.y2, a.x2, a.y2);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return 0.0;
  return std::min(
      {point_seg(a.x1, a.y1, b), point_seg(a.x2, a.y2, b), point_seg(b.x1, b.y1, a), point_seg(b.x2, b.y2, a)});
}

// --- shipped scenarios ---------------------------------------------------------------------------

TEST(ShippedScenarios, AllParseAndNameTheirFile) {
  const auto files = shipped();
  ASSERT_GE(files.size(), 4u);
  std::size_t mdl2e_scenarios = 0;
  for (const auto& f : files) {
    SCOPED_TRACE(f);
    auto sc = load_scenario(f);
    ASSERT_TRUE(sc.ok()) << sc.error();
    EXPECT_EQ(sc->name, fs::path(f).stem().string());
    EXPECT_EQ(sc->file, f);
    EXPECT_EQ(fs::path(sc->base_dir), fs::path(f).parent_path());
    EXPECT_FALSE(sc->description.empty());
    if (sc->world_kind == WorldKind::kMujoco) continue;  // no arena: organism_session_test runs them
    ASSERT_FALSE(sc->robots.empty());
    // Thymio-sized rooms, or a large swarm's floor at the benchmarks' density (4,000 cm^2 a robot).
    EXPECT_GE(sc->world.width, 150);
    EXPECT_GE(sc->world.height, 150);
    const bool room = sc->world.width <= 300 && sc->world.height <= 300;
    const double per_robot = sc->world.width * sc->world.height / static_cast<double>(sc->robots.size());
    EXPECT_TRUE(room || (sc->world.engine == Engine2d::kBox2d && per_robot <= 4000)) << per_robot;
    // The MDL2e demos (the other controllers' scenarios are checked by their own tests).
    if (sc->robots[0].tasks.empty() || sc->robots[0].tasks[0].type != "mdl2e") continue;
    ++mdl2e_scenarios;
    for (const auto& r : sc->robots) {
      // Every robot runs an MDL2e program that exists next to the scenario, wired sensors to
      // controller to motors.
      ASSERT_EQ(r.tasks.size(), 1u);
      EXPECT_EQ(r.tasks[0].type, "mdl2e");
      ASSERT_EQ(r.tasks[0].params.size(), 1u);
      EXPECT_EQ(r.tasks[0].params[0].name, "program");
      EXPECT_TRUE(fs::is_regular_file(fs::path(sc->base_dir) / r.tasks[0].params[0].value))
          << r.tasks[0].params[0].value;
      std::set<std::pair<std::string, std::string>> hooks;
      for (const auto& h : r.hooks) hooks.emplace(h.from, h.to);
      EXPECT_TRUE(hooks.contains({"ir", "controller"}));
      EXPECT_TRUE(hooks.contains({"controller", "wheels"}));
    }
  }
  EXPECT_GE(mdl2e_scenarios, 4u);
}

TEST(ShippedScenarios, EveryGapIsWideEnoughToTurnIn) {
  // Two walls either touch, or leave at least 35 cm between their surfaces; the same for a
  // wall and the arena's sides. So no corridor, door or dead end is narrower than that.
  for (const auto& f : shipped()) {
    SCOPED_TRACE(f);
    auto sc = load_scenario(f);
    ASSERT_TRUE(sc.ok()) << sc.error();
    const auto& w = sc->world;
    std::vector<WallSpec> all = w.walls;
    const WallSpec sides[] = {{0, 0, w.width, 0, 0, {}},
                              {w.width, 0, w.width, w.height, 0, {}},
                              {w.width, w.height, 0, w.height, 0, {}},
                              {0, w.height, 0, 0, 0, {}}};
    for (std::size_t i = 0; i < w.walls.size(); ++i) {
      for (std::size_t j = 0; j < i; ++j) {
        const double gap = segments_distance(all[i], all[j]) - (all[i].thickness + all[j].thickness) / 2;
        EXPECT_TRUE(gap <= 0 || gap >= 35)
            << "walls at lines " << all[i].where.line << " and " << all[j].where.line << " leave " << gap << " cm";
      }
      for (const auto& s : sides) {
        const double gap = segments_distance(all[i], s) - all[i].thickness / 2;
        EXPECT_TRUE(gap <= 1e-9 || gap >= 35)
            << "wall at line " << all[i].where.line << " leaves " << gap << " cm to a side";
      }
    }
  }
}

TEST(ShippedScenarios, MazeIsThePapersDemo) {
  auto sc = load_scenario(kDir + "/maze.yaml");
  ASSERT_TRUE(sc.ok()) << sc.error();
  EXPECT_EQ(sc->seed, 1u);
  EXPECT_EQ(sc->duration, 10min);
  EXPECT_EQ(sc->control_period, 30ms);
  EXPECT_EQ(sc->world.walls.size(), 3u);
  ASSERT_EQ(sc->robots.size(), 1u);
  const RobotSpec& r = sc->robots[0];
  EXPECT_EQ(r.name, "thymio");
  EXPECT_EQ(r.kind, RobotKind::kThymio2);
  EXPECT_DOUBLE_EQ(r.start.theta, std::numbers::pi / 2);
  EXPECT_EQ(r.tasks[0].params[0].value, "mdl2e/obstacle_avoidance.mdl2e");
  ASSERT_EQ(r.hooks.size(), 2u);
  EXPECT_EQ(r.hooks[0].from, "ir");
  EXPECT_EQ(r.hooks[1].to, "wheels");
}

TEST(ShippedScenarios, WallFollowingRunsItsProgram) {
  auto sc = load_scenario(kDir + "/wall_following.yaml");
  ASSERT_TRUE(sc.ok()) << sc.error();
  EXPECT_EQ(sc->robots.at(0).tasks.at(0).params.at(0).value, "mdl2e/wall_following.mdl2e");
}

// --- every field ---------------------------------------------------------------------------------

TEST(ScenarioParser, EveryField) {
  const std::string yaml = R"(name: all_fields
description: Every key there is.
seed: 18446744073709551615
duration: 1.5s
control_period: 20ms
world:
  arena: {width: 300, height: 250.5}
  wall_height: 12
  walls:
    - [20, 50, 120, 50]
    - {from: [120, 50], to: [120, 100], thickness: 3}
robots:
  - name: a
    kind: thymio2
    start: {x: 25, y: 25, heading: -45}
    tasks:
      - name: controller
        type: fake
        params: {gain: 2.5, mode: "two words", flag: true}
        priority: -3
        period: 30ms
        queue: 4
        autostart: false
      - name: logger
        type: fake
    hooks:
      - ir -> controller
      - {from: controller, to: wheels, port: 3, priority: 7, policy: refuse, suppress: 250ms, enabled: false}
      - controller -> logger
)";
  const Scenario sc = parse_ok(yaml);
  EXPECT_EQ(sc.name, "all_fields");
  EXPECT_EQ(sc.description, "Every key there is.");
  EXPECT_EQ(sc.file, "t.yaml");
  EXPECT_EQ(sc.base_dir, ".");
  EXPECT_EQ(sc.seed, 18446744073709551615u);
  EXPECT_EQ(sc.duration, 1500ms);
  EXPECT_EQ(sc.control_period, 20ms);
  EXPECT_EQ(sc.world.width, 300);
  EXPECT_EQ(sc.world.height, 250.5);
  EXPECT_EQ(sc.world.wall_height, 12);
  ASSERT_EQ(sc.world.walls.size(), 2u);
  const WallSpec& w0 = sc.world.walls[0];
  EXPECT_EQ(std::make_tuple(w0.x1, w0.y1, w0.x2, w0.y2, w0.thickness), std::make_tuple(20., 50., 120., 50., 2.));
  EXPECT_EQ(w0.where.str(), "t.yaml:10:7");
  const WallSpec& w1 = sc.world.walls[1];
  EXPECT_EQ(std::make_tuple(w1.x1, w1.y1, w1.x2, w1.y2, w1.thickness), std::make_tuple(120., 50., 120., 100., 3.));
  ASSERT_EQ(sc.robots.size(), 1u);
  const RobotSpec& r = sc.robots[0];
  EXPECT_EQ(r.name, "a");
  EXPECT_EQ(r.where.str(), "t.yaml:13:5");
  EXPECT_DOUBLE_EQ(r.start.x, 25);
  EXPECT_DOUBLE_EQ(r.start.y, 25);
  EXPECT_DOUBLE_EQ(r.start.theta, -std::numbers::pi / 4);
  ASSERT_EQ(r.tasks.size(), 2u);
  const TaskSpec& t = r.tasks[0];
  EXPECT_EQ(t.name, "controller");
  EXPECT_EQ(t.type, "fake");
  EXPECT_EQ(t.where.str(), "t.yaml:17:9");
  EXPECT_EQ(t.type_where.str(), "t.yaml:18:15");
  ASSERT_EQ(t.params.size(), 3u);
  EXPECT_EQ(t.params[0].name, "gain");
  EXPECT_EQ(t.params[0].value, "2.5");
  EXPECT_EQ(t.params[1].value, "two words");
  EXPECT_EQ(t.params[2].value, "true");
  ASSERT_EQ(t.param_where.size(), 3u);
  EXPECT_EQ(t.param_where[1].str(), "t.yaml:19:29");
  EXPECT_EQ(t.priority, -3);
  EXPECT_EQ(t.period, 30ms);
  EXPECT_EQ(t.queue_capacity, 4u);
  EXPECT_FALSE(t.autostart);
  const TaskSpec& t2 = r.tasks[1];
  EXPECT_FALSE(t2.priority.has_value());
  EXPECT_FALSE(t2.period.has_value());
  EXPECT_FALSE(t2.queue_capacity.has_value());
  EXPECT_TRUE(t2.autostart);
  EXPECT_TRUE(t2.params.empty());
  ASSERT_EQ(r.hooks.size(), 3u);
  const HookSpec& h0 = r.hooks[0];
  EXPECT_EQ(h0.from, "ir");
  EXPECT_EQ(h0.to, "controller");
  EXPECT_EQ(h0.options.port, -1);
  EXPECT_EQ(h0.options.priority, 0);
  EXPECT_EQ(h0.options.policy, os::QueuePolicy::kKeepNewest);
  EXPECT_TRUE(h0.options.enabled);
  EXPECT_EQ(h0.options.suppress_window, 0ms);
  EXPECT_EQ(h0.where.str(), "t.yaml:27:9");
  const HookSpec& h1 = r.hooks[1];
  EXPECT_EQ(h1.from, "controller");
  EXPECT_EQ(h1.to, "wheels");
  EXPECT_EQ(h1.options.port, 3);
  EXPECT_EQ(h1.options.priority, 7);
  EXPECT_EQ(h1.options.policy, os::QueuePolicy::kRefuse);
  EXPECT_EQ(h1.options.suppress_window, 250ms);
  EXPECT_FALSE(h1.options.enabled);
}

TEST(ScenarioParser, DefaultsWhenOptionalKeysAreLeftOut) {
  const Scenario sc = parse_ok(kHead + kRobot);
  const Scenario defaults;
  EXPECT_EQ(sc.seed, defaults.seed);
  EXPECT_EQ(sc.duration, defaults.duration);
  EXPECT_EQ(sc.control_period, defaults.control_period);
  EXPECT_EQ(sc.world.wall_height, WorldSpec{}.wall_height);
  EXPECT_TRUE(sc.description.empty());
  EXPECT_EQ(sc.robots.at(0).start.theta, 0);
  EXPECT_TRUE(sc.robots.at(0).tasks.empty());
}

TEST(ScenarioParser, BaseDirIsTheFilesDirectory) {
  auto sc = parse_scenario(kHead + kRobot, "some/where/t.yaml");
  ASSERT_TRUE(sc.ok()) << sc.error();
  EXPECT_EQ(sc->base_dir, "some/where");
}

// --- hooks ---------------------------------------------------------------------------------------

TEST(ScenarioParser, ShortHooksChainAndQuote) {
  const Scenario sc = parse_ok(kHead + kRobot +
                               "    tasks:\n"
                               "      - {name: a, type: x}\n"
                               "      - {name: b, type: x}\n"
                               "    hooks:\n"
                               "      - ir->a -> b  ->wheels\n"
                               "      - \"b -> a\"\n");
  const auto& h = sc.robots.at(0).hooks;
  ASSERT_EQ(h.size(), 4u);
  EXPECT_EQ(std::make_pair(h[0].from, h[0].to), std::make_pair(std::string("ir"), std::string("a")));
  EXPECT_EQ(std::make_pair(h[1].from, h[1].to), std::make_pair(std::string("a"), std::string("b")));
  EXPECT_EQ(std::make_pair(h[2].from, h[2].to), std::make_pair(std::string("b"), std::string("wheels")));
  EXPECT_EQ(std::make_pair(h[3].from, h[3].to), std::make_pair(std::string("b"), std::string("a")));
  // Each hook of a chain is located at its sender's name.
  EXPECT_EQ(h[0].where.str(), "t.yaml:13:9");
  EXPECT_EQ(h[1].where.str(), "t.yaml:13:13");
  EXPECT_EQ(h[2].where.str(), "t.yaml:13:18");
  EXPECT_EQ(h[3].where.str(), "t.yaml:14:10");
}

TEST(ScenarioParser, HookErrors) {
  const std::string tasks = kHead + kRobot +
                            "    tasks:\n"
                            "      - {name: controller, type: x}\n"
                            "    hooks:\n";
  // Lines: 9 tasks, 10 the task, 11 hooks, 12 the hook.
  expect_error(tasks + "      - ir -> controler\n",
               "t.yaml:12:15: ", "robot 'r' has no task 'controler' (did you mean 'controller'?)");
  expect_error(tasks + "      - {from: controller, to: whels}\n",
               "t.yaml:12:32: ", "has no task 'whels' (did you mean 'wheels'?)");
  expect_error(tasks + "      - controller -> controller\n", "t.yaml:12:9: ", "hooked to itself");
  expect_error(tasks + "      - ir -> controller\n      - {from: ir, to: controller}\n",
               "t.yaml:13:9: ", "hook ir -> controller is given twice (first at line 12)");
  expect_error(tasks + "      - ir controller\n", "t.yaml:12:9: ", "is not a task name");
  expect_error(tasks + "      - ir ->\n", "t.yaml:12:14: ", "is missing a task name");
  expect_error(tasks + "      - controller\n", "t.yaml:12:9: ", "needs an arrow");
  expect_error(tasks + "      - {from: ir, to: controller, policy: newest}\n",
               "t.yaml:12:44: ", "policy must be keep_newest or refuse, got 'newest'");
  expect_error(tasks + "      - {from: ir, to: controller, port: 70000}\n",
               "t.yaml:12:42: ", "port must be an integer in 0..65535");
  expect_error(tasks + "      - {from: ir, to: controller, suppres: 1s}\n",
               "t.yaml:12:36: ", "unknown key 'suppres' in a hook (did you mean 'suppress'?)");
  expect_error(tasks + "      - {from: ir}\n", "t.yaml:12:9: ", "a hook needs 'to'");
  expect_error(tasks + "      - [ir, controller]\n", "t.yaml:12:9: ", "a hook is 'sender -> receiver' or");
  expect_error(tasks + "      - {from: ir, to: controller, suppress: 2h}\n",
               "t.yaml:12:46: ", "suppress must be between 0s and 3600s");
}

// --- count ---------------------------------------------------------------------------------------

const std::string kSwarm =
    "name: s\n"
    "seed: SEED\n"
    "world:\n"
    "  arena: {width: 200, height: 200}\n"
    "  walls: [[100, 0, 100, 120], [40, 160, 160, 160]]\n"
    "robots:\n"
    "  - name: lead\n"
    "    start: {x: 20, y: 20}\n"
    "  - name: bot\n"
    "    count: COUNT\n"
    "    start: random\n"
    "    tasks: [{name: c, type: x}]\n"
    "    hooks: [ir -> c -> wheels]\n";

std::string swarm(int seed, int count) {
  std::string s = kSwarm;
  s.replace(s.find("SEED"), 4, std::to_string(seed));
  s.replace(s.find("COUNT"), 5, std::to_string(count));
  return s;
}

TEST(ScenarioCount, ExpandsWithIndexedNamesAndSameTasks) {
  const Scenario sc = parse_ok(swarm(5, 20));
  ASSERT_EQ(sc.robots.size(), 21u);
  EXPECT_EQ(sc.robots[0].name, "lead");
  for (int i = 0; i < 20; ++i) {
    const RobotSpec& r = sc.robots[static_cast<std::size_t>(i) + 1];
    EXPECT_EQ(r.name, "bot" + std::to_string(i));
    ASSERT_EQ(r.tasks.size(), 1u);
    EXPECT_EQ(r.tasks[0].name, "c");
    EXPECT_EQ(r.hooks.size(), 2u);
    EXPECT_EQ(r.where.line, 9);
  }
}

TEST(ScenarioCount, RandomStartsAreClearAndFollowTheSeed) {
  const Scenario a = parse_ok(swarm(5, 30));
  const Scenario b = parse_ok(swarm(5, 30));
  const Scenario c = parse_ok(swarm(6, 30));
  ASSERT_EQ(a.robots.size(), 31u);
  int differ = 0;
  for (std::size_t i = 0; i < a.robots.size(); ++i) {
    const Pose& p = a.robots[i].start;
    EXPECT_EQ(p.x, b.robots[i].start.x);
    EXPECT_EQ(p.y, b.robots[i].start.y);
    EXPECT_EQ(p.theta, b.robots[i].start.theta);
    if (p.x != c.robots[i].start.x || p.y != c.robots[i].start.y) ++differ;
    EXPECT_GE(p.theta, -std::numbers::pi);
    EXPECT_LE(p.theta, std::numbers::pi);
    EXPECT_GE(std::min({p.x, p.y, 200 - p.x, 200 - p.y}), kStartClearance);
    // Clear of both walls (thickness 2) ...
    const double d1 = (p.y <= 120 ? std::abs(p.x - 100) : std::hypot(p.x - 100, p.y - 120)) - 1;
    const double d2 =
        (p.x >= 40 && p.x <= 160 ? std::abs(p.y - 160)
                                 : std::min(std::hypot(p.x - 40, p.y - 160), std::hypot(p.x - 160, p.y - 160))) -
        1;
    EXPECT_GE(d1, kStartClearance) << a.robots[i].name;
    EXPECT_GE(d2, kStartClearance) << a.robots[i].name;
    // ... and of each other.
    for (std::size_t j = 0; j < i; ++j)
      EXPECT_GE(std::hypot(p.x - a.robots[j].start.x, p.y - a.robots[j].start.y), 2 * kStartClearance);
  }
  EXPECT_GT(differ, 20);
}

TEST(ScenarioCount, ExplicitStartList) {
  const Scenario sc = parse_ok(kHead +
                               "  - name: r\n"
                               "    count: 2\n"
                               "    start: [{x: 20, y: 20}, {x: 50, y: 80, heading: 180}]\n");
  ASSERT_EQ(sc.robots.size(), 2u);
  EXPECT_EQ(sc.robots[0].name, "r0");
  EXPECT_EQ(sc.robots[1].name, "r1");
  EXPECT_EQ(sc.robots[1].start.x, 50);
  EXPECT_DOUBLE_EQ(sc.robots[1].start.theta, std::numbers::pi);
}

TEST(ScenarioCount, Errors) {
  expect_error(swarm(1, 200), "t.yaml:11:12: ", "no room for 200 robots here: only ");
  expect_error(swarm(1, 0), "t.yaml:10:12: ", "count must be an integer in 1..20000");
  expect_error(swarm(1, 20001), "t.yaml:10:12: ", "count must be an integer in 1..20000");
  expect_error(kHead + "  - {name: r, count: 3, start: {x: 20, y: 20}}\n",
               "t.yaml:7:32: ", "3 robots cannot all start at one pose");
  expect_error(kHead + "  - {name: r, count: 3, start: [{x: 20, y: 20}]}\n",
               "t.yaml:7:32: ", "start lists 1 poses for 3 robots");
  expect_error(kHead + "  - {name: r, count: 2, start: random}\n  - {name: r1, start: {x: 20, y: 20}}\n",
               "t.yaml:8:5: ", "robot name 'r1' is already used (line 7)");
  expect_error(kHead + "  - {name: r, count: 2, start: [{x: 20, y: 20}, {x: 30, y: 20}]}\n",
               "t.yaml:7:49: ", "is 10 cm from another robot's start (20, 20)");
}

// --- errors, each located ------------------------------------------------------------------------

TEST(ScenarioErrors, Structure) {
  expect_error("nmae: t\n", "t.yaml:1:1: ", "unknown key 'nmae' in the scenario (did you mean 'name'?)");
  expect_error("name: t\nzzz: 1\n", "t.yaml:2:1: ", "unknown key 'zzz' in the scenario (known keys: name");
  expect_error("name: t\nworld: {arena: {width: 100, height: 100}}\n", "t.yaml:1:1: ", "the scenario needs 'robots'");
  expect_error(kHead + kRobot + "name: u\n",
               "t.yaml:9:1: ", "key 'name' given twice in the scenario (first at line 1)");
  expect_error("- name: t\n", "t.yaml:1:1: ", "the scenario must be a mapping");
  expect_error("", "t.yaml:1:1: ", "the scenario is empty");
  expect_error("# only a comment\n", "t.yaml:1:1: ", "the scenario is empty");
  expect_error("name: t\nworld: [1, 2\n", "t.yaml:2:", "invalid YAML");
  expect_error("name: t\n---\nname: u\n", "t.yaml:2:", "one YAML document");
  expect_error(kHead + "  - {name: r, start: {x: 50, y: 50}, tasks: 5}\n", "t.yaml:7:45: ", "tasks must be a list");
  expect_error(kHead + "  - {name: r, start: {x: 50, y: 50}, [a]: 5}\n",
               "t.yaml:7:38: ", "a key in a robot must be a plain name");
  expect_error("name: t\nrobots: []\nworld: {arena: {width: 100, height: 100}}\n", "t.yaml:2:9: ", "robots is empty");
}

TEST(ScenarioErrors, Values) {
  expect_error("name: 1t\n", "t.yaml:1:7: ", "name '1t' is not a valid name");
  expect_error("name: t\nseed: -1\n", "t.yaml:2:7: ", "seed must be an unsigned integer");
  expect_error("name: t\nseed: [1]\n", "t.yaml:2:7: ", "seed must be a single value, got a sequence");
  expect_error("name: t\nduration: 10\n", "t.yaml:2:11: ", "duration: '10' has no unit");
  expect_error("name: t\nduration: 0s\n", "t.yaml:2:11: ", "duration must be between 1ms and");
  expect_error("name: t\ncontrol_period: 5s\n", "t.yaml:2:17: ", "control_period must be between 1ms and 1s");
  const std::string w = "name: t\nworld:\n  arena: {width: ";
  expect_error(w + "inf, height: 100}\n", "t.yaml:3:18: ", "arena width (cm) must be a finite number, got 'inf'");
  expect_error(w + "nan, height: 100}\n", "t.yaml:3:18: ", "must be a finite number");
  expect_error(w + "1e999, height: 100}\n", "t.yaml:3:18: ", "must be a finite number");
  expect_error(w + "0, height: 100}\n", "t.yaml:3:18: ", "arena width (cm) must be in 16..10000, got 0");
  expect_error(w + "1O0, height: 100}\n", "t.yaml:3:18: ", "must be a finite number, got '1O0'");
  expect_error(w + "100}\n", "t.yaml:3:10: ", "arena needs 'height'");
  expect_error(w + "100, heigth: 100}\n", "t.yaml:3:23: ", "unknown key 'heigth' in arena (did you mean 'height'?)");
  expect_error("name: t\nworld:\n  arena: [100, 100]\n", "t.yaml:3:10: ", "arena must be a mapping");
  expect_error(kHead + "  - {name: r, start: {x: 50, y: 50, heading: 400}}\n",
               "t.yaml:7:46: ", "heading (degrees) must be in -360..360");
  expect_error(kHead + "  - {name: r, kind: e-puck, start: {x: 50, y: 50}}\n",
               "t.yaml:7:21: ", "unknown robot kind 'e-puck' (the only kind is thymio2)");
  const std::string task = kHead + kRobot + "    tasks:\n      - name: c\n        type: x\n";
  // Lines: 9 tasks, 10 "- name: c", 11 type, 12 the line under test.
  expect_error(task + "        priority: 5000\n", "t.yaml:12:19: ", "priority must be an integer in -1000..1000");
  expect_error(task + "        priority: 1.5\n", "t.yaml:12:19: ", "priority must be an integer");
  expect_error(task + "        queue: 0\n", "t.yaml:12:16: ", "queue must be an integer in 1..65536");
  expect_error(task + "        period: fast\n", "t.yaml:12:17: ", "period: 'fast' has no unit");
  expect_error(task + "        autostart: yes\n", "t.yaml:12:20: ", "autostart must be true or false");
  expect_error(task + "        params: {a: [1, 2]}\n", "t.yaml:12:21: ", "parameter 'a' needs a single value");
  expect_error(task + "        params: {a:}\n", "t.yaml:12:18: ", "parameter 'a' needs a single value");
  expect_error(task + "        params: {a: 1, a: 2}\n", "t.yaml:12:24: ", "parameter 'a' given twice");
  expect_error(task + "        params: [a, b]\n", "t.yaml:12:17: ", "params must be a mapping");
  expect_error(task + "        priorty: 1\n",
               "t.yaml:12:9: ", "unknown key 'priorty' in a task (did you mean 'priority'?)");
}

TEST(ScenarioErrors, Names) {
  expect_error(kHead + "  - {name: 'a b', start: {x: 50, y: 50}}\n",
               "t.yaml:7:12: ", "robot name 'a b' is not a valid name");
  expect_error(kHead + kRobot + kRobot, "t.yaml:9:5: ", "robot name 'r' is already used (line 7)");
  const std::string tasks = kHead + kRobot + "    tasks:\n";
  expect_error(tasks + "      - {name: c, type: x}\n      - {name: c, type: y}\n",
               "t.yaml:11:9: ", "robot 'r' already has a task 'c' (line 10)");
  expect_error(tasks + "      - {name: ir, type: x}\n", "t.yaml:10:9: ", "task name 'ir' is taken");
  expect_error(tasks + "      - {name: wheels, type: x}\n", "t.yaml:10:9: ", "task name 'wheels' is taken");
  expect_error(tasks + "      - {name: 9c, type: x}\n", "t.yaml:10:16: ", "task name '9c' is not a valid task name");
  expect_error(tasks + "      - {name: c, type: 'x y'}\n", "t.yaml:10:25: ", "task type 'x y' is not a valid");
  expect_error(tasks + "      - {name: c}\n", "t.yaml:10:9: ", "a task needs 'type'");
}

TEST(ScenarioErrors, Geometry) {
  const std::string head = "name: t\nworld:\n  arena: {width: 200, height: 100}\n  walls:\n";
  const std::string rest = "robots:\n  - {name: r, start: {x: 50, y: 50}}\n";
  expect_error(head + "    - [10, 10, 10, 10]\n" + rest, "t.yaml:5:7: ", "zero length");
  expect_error(head + "    - [10, 10, 250, 10]\n" + rest, "t.yaml:5:16: ", "wall x2 must be in 0..200, got 250");
  expect_error(head + "    - {from: [10, 10], to: [10, -5]}\n" + rest, "t.yaml:5:33: ", "y must be in 0..100");
  expect_error(head + "    - {from: [10, 10], to: [10]}\n" + rest, "t.yaml:5:28: ", "wall 'to' must be a point [x, y]");
  expect_error(head + "    - {from: [10, 10], to: [20, 10], thickness: 0}\n" + rest,
               "t.yaml:5:49: ", "wall thickness (cm) must be in 0.1..50");
  expect_error(head + "    - [10, 10, 20]\n" + rest, "t.yaml:5:7: ", "this one has 3 numbers");
  expect_error(head + "    - 5\n" + rest, "t.yaml:5:7: ", "a wall is [x1, y1, x2, y2] or");
  // Starts (line 6 is the robot; its start map begins at column 22).
  const std::string walls = "name: t\nworld:\n  arena: {width: 200, height: 100}\n  walls: [[100, 0, 100, 60]]\n";
  auto robot = [&](const std::string& start) { return walls + "robots:\n  - {name: r, start: " + start + "}\n"; };
  expect_error(robot("{x: 250, y: 50}"), "t.yaml:6:22: ", "start (250, 50) is outside the arena");
  expect_error(robot("{x: 5, y: 50}"), "t.yaml:6:22: ", "start (5, 50) is 5 cm from the arena's side");
  expect_error(robot("{x: 93, y: 50}"), "t.yaml:6:22: ", "start (93, 50) is 6 cm from the wall at line 4");
  expect_error(robot("{x: 100, y: 30}"), "t.yaml:6:22: ", "start (100, 30) is inside the wall at line 4");
  // Past the wall's end: the distance is to the end point.
  EXPECT_TRUE(parse_scenario(robot("{x: 100, y: 70}"), "t.yaml").ok());
  expect_error(robot("{x: 100, y: 66}"), "t.yaml:6:22: ", "is 5 cm from the wall");
  expect_error(walls + "robots:\n  - {name: a, start: {x: 20, y: 20}}\n  - {name: b, start: {x: 30, y: 25}}\n",
               "t.yaml:7:22: ", "cm from another robot's start (20, 20); starts must be at least 16 cm apart");
}

TEST(ScenarioErrors, HostileInput) {
  // Deep nesting in flow and block style stops at 64 levels, long before the stack is at risk.
  std::string flow = "name: t\nworld: " + std::string(5000, '[') + std::string(5000, ']') + "\n";
  expect_error(flow, "t.yaml:2:", "nested more than 64 levels deep");
  std::string block = "name: t\n";
  for (int i = 0; i < 100; ++i)
    block += std::string(static_cast<std::size_t>(i) * 2, ' ') + "k" + std::to_string(i) + ":\n";
  expect_error(block, "t.yaml:", "nested more than 64 levels deep");
  std::string dashes = "- " + std::string(0, ' ');
  for (int i = 0; i < 200; ++i) dashes += "- ";
  expect_error(dashes + "x\n", "t.yaml:1:", "nested more than 64 levels deep");
  // Too big.
  std::string big = "name: t\ndescription: \"" + std::string(kMaxScenarioBytes, 'x') + "\"\n";
  expect_error(big, "t.yaml:1:1: ", "at most 1 MiB");
  // Bytes that are not text.
  std::string junk;
  for (int i = 0; i < 256; ++i) junk.push_back(static_cast<char>(i));
  auto r = parse_scenario(junk, "t.yaml");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().rfind("t.yaml:1:", 0), 0u) << r.error();
  // Aliases are followed, but cannot multiply work past the limits.
  std::string alias = kHead + "  - &r {name: r, count: 20000, start: random}\n";
  for (int i = 0; i < 5; ++i) alias += "  - *r\n";
  expect_error(alias, "t.yaml:", "more than 20000 robots");
}

TEST(ScenarioErrors, CopiesCannotMultiplyTheWork) {
  // One task with 64 parameters, copied into 1000 robots, is more than a scenario may hold.
  std::string params;
  for (int k = 0; k < 64; ++k) params += "p" + std::to_string(k) + ": 1, ";
  expect_error(
      "name: t\nworld: {arena: {width: 1000, height: 1000}}\nrobots:\n"
      "  - {name: r, count: 1000, start: random, tasks: [{name: a, type: x, params: {" +
          params + "}}, {name: b, type: x, params: {" + params + "}}, {name: c, type: x, params: {" + params +
          "}}, {name: d, type: x, params: {" + params + "}}]}\n",
      "t.yaml:4:5: ", "too big: more than");
  // The most walls and robots there may be: placement stays quick and correct.
  std::string walls = "name: t\nworld:\n  arena: {width: 5000, height: 5000}\n  walls:\n    - &d [0, 0, 5000, 5000]\n";
  for (int i = 1; i < static_cast<int>(kMaxWalls); ++i) walls += "    - *d\n";
  const Scenario sc = parse_ok(walls + "robots:\n  - {name: r, count: 1000, start: random}\n");
  ASSERT_EQ(sc.robots.size(), 1000u);
  for (const auto& r : sc.robots)
    EXPECT_GE(std::abs(r.start.x - r.start.y) / std::numbers::sqrt2, kStartClearance + 1) << r.name;
}

TEST(LoadScenario, MissingFileAndDirectory) {
  auto r = load_scenario(kDir + "/no_such.yaml");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().rfind(kDir + "/no_such.yaml: cannot open the scenario file", 0), 0u) << r.error();
  auto d = load_scenario(kDir);
  ASSERT_FALSE(d.ok());
  EXPECT_NE(d.error().find("not a regular file"), std::string::npos);
}

// --- check_scenario ------------------------------------------------------------------------------

os::TaskTypeRegistry fake_registry() {
  os::TaskTypeRegistry reg;
  os::TaskType t;
  t.name = "fake";
  t.params = {{"gain", os::ParamType::kReal, 1.0, 0.0, 10.0, "how much"},
              {"mode", os::ParamType::kString, std::string("plain"), std::nullopt, std::nullopt, "how"},
              {"flag", os::ParamType::kBool, false, std::nullopt, std::nullopt, "whether"}};
  t.make = [](const os::ParamSet&) { return std::unique_ptr<os::Task>(); };
  EXPECT_TRUE(reg.add(t).ok());
  t.name = "fake_sensor";
  t.params.clear();
  EXPECT_TRUE(reg.add(t).ok());
  return reg;
}

std::string checked(const std::string& task_lines) {
  const std::string yaml = kHead + kRobot + "    tasks:\n" + task_lines;
  auto sc = parse_scenario(yaml, "t.yaml");
  EXPECT_TRUE(sc.ok()) << sc.error();
  if (!sc.ok()) return "parse failed";
  auto st = check_scenario(*sc, fake_registry());
  return st.ok() ? "ok" : st.error();
}

TEST(CheckScenario, TypesAndParameters) {
  // Lines: 9 tasks, 10 the task, 11 its type, 12 params.
  EXPECT_EQ(checked("      - name: c\n        type: fake\n        params: {gain: 2, mode: fast, flag: true}\n"), "ok");
  EXPECT_EQ(checked("      - name: c\n        type: fak\n"),
            "t.yaml:11:15: unknown task type 'fak' (did you mean 'fake'?)");
  EXPECT_EQ(checked("      - name: c\n        type: fake\n        params:\n          gain: 2\n          gian: 3\n"),
            "t.yaml:14:11: task 'c': task type 'fake' has no parameter 'gian' (did you mean 'gain'?)");
  const std::string bad = checked("      - name: c\n        type: fake\n        params: {mode: x, gain: 11}\n");
  EXPECT_EQ(bad.rfind("t.yaml:12:27: task 'c': ", 0), 0u) << bad;
  EXPECT_NE(bad.find("gain"), std::string::npos) << bad;
  const std::string flag = checked("      - name: c\n        type: fake\n        params: {flag: maybe}\n");
  EXPECT_EQ(flag.rfind("t.yaml:12:18: task 'c': ", 0), 0u) << flag;
}

TEST(CheckScenario, ShippedScenariosAgainstTheRealTaskTypes) {
  // Every type a scenario may name (robot and control layers), as a run registers them.
  os::TaskTypeRegistry reg;
  ASSERT_TRUE(register_scenario_task_types(reg, RobotDevices{}, file_program_reader(kDir)).ok());
  for (const auto& f : shipped()) {
    auto sc = load_scenario(f);
    ASSERT_TRUE(sc.ok()) << sc.error();
    auto st = check_scenario(*sc, reg);
    EXPECT_TRUE(st.ok()) << st.error();
  }
  os::TaskTypeRegistry empty;
  auto sc = load_scenario(kDir + "/maze.yaml");
  ASSERT_TRUE(sc.ok());
  auto st = check_scenario(*sc, empty);
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.error().rfind(kDir + "/maze.yaml:26:15: unknown task type 'mdl2e'", 0), 0u) << st.error();
}

// yaml-cpp builds its events by recursion, one frame per level; the first pass stops it at
// kMaxNesting, before the tree is built, so the deepest input a file can hold (a MiB of '[' or '{',
// closed or not, or of '- ' and '? ') is a located error on a stack of 1/32 of a thread's default.
TEST(ScenarioErrors, AMegabyteOfNestingStopsAtTheBoundOnASmallStack) {
  const std::size_t n = kMaxScenarioBytes - 64;
  const std::vector<std::string> inputs = {
      "name: t\nworld: " + std::string(n / 2, '[') + std::string(n / 2, ']') + "\n",
      "name: t\nworld: " + std::string(n, '[') + "\n",
      "name: t\nworld: " + std::string(n, '{') + "\n",
      "name: t\nworld: " +
          [&] {
            std::string s;
            while (s.size() < n) s += "{a: ";
            return s;
          }(),
      [&] {
        std::string s;
        while (s.size() < n) s += "- ";
        return s + "x\n";
      }(),
      [&] {
        std::string s;
        while (s.size() < n) s += "? ";
        return s + "x\n";
      }(),
  };
  std::vector<std::string> errors(inputs.size());
  ASSERT_TRUE(test_support::run_on_small_stack([&] {
    for (std::size_t i = 0; i < inputs.size(); ++i) {
      auto sc = parse_scenario(inputs[i], "t.yaml");
      errors[i] = sc.ok() ? "<accepted>" : sc.error();
    }
  }));
  for (const std::string& e : errors) {
    EXPECT_EQ(e.rfind("t.yaml:", 0), 0u) << e;
    EXPECT_NE(e.find("nested more than 64 levels deep"), std::string::npos) << e;
  }
}

// The byte pass that stops deep flow nesting before yaml-cpp reads it counts only brackets that
// open collections: brackets in quotes, comments, block scalars and inside plain words pass.
TEST(ScenarioErrors, BracketsThatOpenNoCollectionAreNotNesting) {
  const std::string many(100, '[');
  const std::string yaml = "name: t  # " + many + "\ndescription: |\n" +
                           [&] {
                             std::string lines;
                             for (int i = 0; i < 100; ++i) lines += "  " + many + " {\n";
                             return lines;
                           }() +
                           kHead.substr(8) + kRobot + "    tasks:\n      - {name: x, type: '" + many +
                           "', program: \"" + many + "\\\"\"}\n";
  auto sc = parse_scenario(yaml, "t.yaml");
  const std::string e = sc.ok() ? std::string() : sc.error();
  EXPECT_EQ(e.find("nested more than"), std::string::npos) << e;
  EXPECT_NE(e.find("unknown key 'program'"), std::string::npos) << e;  // the YAML was read to its end
}

}  // namespace
}  // namespace symb::sim
