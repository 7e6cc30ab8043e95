// world.engine in scenario files (enki | box2d), make_world, and the robot limit and random
// placement that swarms of thousands need.
#include <cmath>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "symb/sim/box2d/box2d_world.hpp"
#include "symb/sim/enki_world.hpp"
#include "symb/sim/scenario.hpp"
#include "symb/sim/world_factory.hpp"

namespace symb::sim {
namespace scenario_engine_test {
namespace {

std::string with_world(const std::string& world_lines,
                       const std::string& robots = "  - name: r\n    start: {x: 50, y: 50}\n") {
  return "name: t\nworld:\n" + world_lines + "robots:\n" + robots;
}

void expect_error(const std::string& yaml, const std::string& where, const std::string& what) {
  auto sc = parse_scenario(yaml, "t.yaml");
  ASSERT_FALSE(sc.ok()) << "accepted:\n" << yaml;
  EXPECT_EQ(sc.error().substr(0, where.size()), where) << sc.error();
  EXPECT_NE(sc.error().find(what), std::string::npos) << "'" << what << "' not in: " << sc.error();
}

TEST(ScenarioEngine, DefaultsToEnkiAndReadsBox2d) {
  auto plain = parse_scenario(with_world("  arena: {width: 200, height: 100}\n"), "t.yaml");
  ASSERT_TRUE(plain.ok()) << plain.error();
  EXPECT_EQ(plain->world.engine, Engine2d::kEnki);
  auto enki = parse_scenario(with_world("  engine: enki\n  arena: {width: 200, height: 100}\n"), "t.yaml");
  ASSERT_TRUE(enki.ok()) << enki.error();
  EXPECT_EQ(enki->world.engine, Engine2d::kEnki);
  auto box2d = parse_scenario(with_world("  engine: box2d\n  arena: {width: 200, height: 100}\n"), "t.yaml");
  ASSERT_TRUE(box2d.ok()) << box2d.error();
  EXPECT_EQ(box2d->world.engine, Engine2d::kBox2d);
  EXPECT_STREQ(engine_name(Engine2d::kBox2d), "box2d");
  EXPECT_STREQ(engine_name(Engine2d::kEnki), "enki");
}

TEST(ScenarioEngine, BadEnginesAreLocatedErrors) {
  expect_error(with_world("  engine: bullet\n  arena: {width: 200, height: 100}\n"),
               "t.yaml:3:11:", "unknown world engine 'bullet'");
  expect_error(with_world("  engine: [box2d]\n  arena: {width: 200, height: 100}\n"), "t.yaml:3:11:", "engine");
  expect_error(with_world("  engine: Box2D\n  arena: {width: 200, height: 100}\n"), "t.yaml:3:11:", "box2d");
  // A 3D world runs on MuJoCo: naming a 2D engine there is a mistake, not a no-op.
  expect_error("name: t\nworld: {kind: mujoco, engine: box2d}\nrobots:\n  - name: m\n    module: cube.yaml\n",
               "t.yaml:2:31:", "a 3D world (kind: mujoco) runs on MuJoCo");
}

TEST(ScenarioEngine, MakeWorldBuildsTheNamedEngine) {
  WorldSpec spec;
  spec.width = 200;
  spec.height = 100;
  auto enki = make_world(spec, 1, 3);
  EXPECT_NE(dynamic_cast<EnkiWorld*>(enki.get()), nullptr);
  spec.engine = Engine2d::kBox2d;
  auto box2d = make_world(spec, 1, 3);
  EXPECT_NE(dynamic_cast<Box2DWorld*>(box2d.get()), nullptr);
  box2d->add_robot("a", RobotKind::kThymio2, {50, 50, 0});
  box2d->step(0.03);
  EXPECT_EQ(box2d->steps(), 1u);
  spec.width = -1;
  EXPECT_THROW(make_world(spec, 1, 3), std::invalid_argument);
}

// Every pair of starts at least 16 cm apart, checked through a grid of 16 cm cells.
std::size_t too_close_pairs(const std::vector<RobotSpec>& robots) {
  std::map<std::pair<long, long>, std::vector<Pose>> cells;
  std::size_t bad = 0;
  for (const RobotSpec& r : robots) {
    const long cx = static_cast<long>(std::floor(r.start.x / 16)), cy = static_cast<long>(std::floor(r.start.y / 16));
    for (long dy = -1; dy <= 1; ++dy)
      for (long dx = -1; dx <= 1; ++dx) {
        auto it = cells.find({cx + dx, cy + dy});
        if (it == cells.end()) continue;
        for (const Pose& q : it->second)
          if (std::hypot(q.x - r.start.x, q.y - r.start.y) < 16) ++bad;
      }
    cells[{cx, cy}].push_back(r.start);
  }
  return bad;
}

TEST(ScenarioEngine, TenThousandRandomStartsAreClearOfEachOtherAndTheWalls) {
  // Equal density: 4,000 cm2 per robot, a 63 m square with a few long walls.
  const std::string yaml = with_world(
      "  engine: box2d\n"
      "  arena: {width: 6325, height: 6325}\n"
      "  walls:\n"
      "    - [1000, 0, 1000, 4000]\n"
      "    - [3000, 6325, 3000, 2000]\n"
      "    - [0, 3000, 2500, 3000]\n",
      "  - name: t\n    count: 10000\n    start: random\n");
  auto sc = parse_scenario(yaml, "t.yaml");
  ASSERT_TRUE(sc.ok()) << sc.error();
  ASSERT_EQ(sc->robots.size(), 10000u);
  EXPECT_EQ(too_close_pairs(sc->robots), 0u);
  for (const RobotSpec& r : sc->robots) {
    ASSERT_GE(std::abs(r.start.x - 1000) > 9 || r.start.y > 4009, true) << r.name;  // 8 cm + half the 2 cm wall
    ASSERT_GE(std::min({r.start.x, r.start.y, 6325 - r.start.x, 6325 - r.start.y}), 8.0) << r.name;
  }
  EXPECT_EQ(sc->robots[9999].name, "t9999");
  // The same seed places them alike.
  auto again = parse_scenario(yaml, "t.yaml");
  ASSERT_TRUE(again.ok());
  for (std::size_t i = 0; i < 10000; i += 997) {
    EXPECT_EQ(again->robots[i].start.x, sc->robots[i].start.x);
    EXPECT_EQ(again->robots[i].start.theta, sc->robots[i].start.theta);
  }
}

TEST(ScenarioEngine, TheRobotLimitIsTwentyThousand) {
  EXPECT_EQ(kMaxRobots, 20000u);
  const std::string arena = "  engine: box2d\n  arena: {width: 10000, height: 10000}\n";
  auto full = parse_scenario(with_world(arena, "  - name: t\n    count: 20000\n    start: random\n"), "t.yaml");
  ASSERT_TRUE(full.ok()) << full.error();
  EXPECT_EQ(full->robots.size(), 20000u);
  EXPECT_EQ(too_close_pairs(full->robots), 0u);
  expect_error(with_world(arena, "  - name: t\n    count: 20001\n    start: random\n"), "t.yaml:7:12:", "20000");
  expect_error(with_world(arena,
                          "  - name: t\n    count: 20000\n    start: random\n"
                          "  - name: u\n    start: {x: 50, y: 50}\n"),
               "t.yaml:9:5:", "more than 20000 robots");
}

TEST(ScenarioEngine, ExplicitStartsTooCloseNameTheFirstNeighbour) {
  expect_error(with_world("  arena: {width: 400, height: 100}\n",
                          "  - name: a\n    start: {x: 50, y: 50}\n"
                          "  - name: b\n    start: {x: 100, y: 50}\n"
                          "  - name: c\n    start: {x: 60, y: 50}\n"),
               "t.yaml:10:12:", "10 cm from another robot's start (50, 50)");
}

}  // namespace
}  // namespace scenario_engine_test
}  // namespace symb::sim
