#include "symb/sim/enki_world.hpp"

#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <numbers>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "symb/sim/maze_generator.hpp"

namespace symb::sim {
namespace {

constexpr double kDt = 0.03;

WorldSpec empty_arena(double w = 200, double h = 100) {
  WorldSpec s;
  s.width = w;
  s.height = h;
  return s;
}

WorldSpec with_wall(WallSpec wall, double w = 200, double h = 100) {
  WorldSpec s = empty_arena(w, h);
  s.walls.push_back(wall);
  return s;
}

WallSpec vertical_wall(double x, double y1, double y2) {
  WallSpec w;
  w.x1 = w.x2 = x;
  w.y1 = y1;
  w.y2 = y2;
  w.thickness = 2;
  return w;
}

TEST(EnkiWorld, DrivingStraightCoversTheExpectedDistance) {
  EnkiWorld world(empty_arena(), 1);
  const std::size_t r = world.add_robot("a", RobotKind::kThymio2, {20, 50, 0});
  world.set_wheels(r, 10, 10);
  for (int i = 0; i < 100; ++i) world.step(kDt);  // 3 s at 10 cm/s
  const RobotState s = world.state(r);
  EXPECT_NEAR(s.pose.x, 50, 1.0);
  EXPECT_NEAR(s.pose.y, 50, 1.0);
  EXPECT_NEAR(s.distance, 30, 1.0);
  EXPECT_NEAR(world.time(), 3.0, 1e-9);
  EXPECT_EQ(world.steps(), 100u);
  EXPECT_EQ(s.contact_steps, 0u);
  EXPECT_FALSE(s.in_contact);
}

TEST(EnkiWorld, WheelSpeedsAreClampedToTheThymioLimit) {
  EnkiWorld world(empty_arena(400, 100), 1);
  const std::size_t r = world.add_robot("a", RobotKind::kThymio2, {20, 50, 0});
  world.set_wheels(r, 100, 1e9);
  EXPECT_DOUBLE_EQ(world.state(r).left_speed, kMaxWheelSpeed);
  EXPECT_DOUBLE_EQ(world.state(r).right_speed, kMaxWheelSpeed);
  for (int i = 0; i < 100; ++i) world.step(kDt);
  EXPECT_NEAR(world.state(r).distance, 3 * kMaxWheelSpeed, 1.5);
  world.set_wheels(r, -100, -100);
  EXPECT_DOUBLE_EQ(world.state(r).left_speed, -kMaxWheelSpeed);
}

TEST(EnkiWorld, TurningOnTheSpotKeepsThePosition) {
  EnkiWorld world(empty_arena(), 3);
  const std::size_t r = world.add_robot("a", RobotKind::kThymio2, {100, 50, 0});
  world.set_wheels(r, -5, 5);  // counter-clockwise
  for (int i = 0; i < 10; ++i) world.step(kDt);
  const RobotState s = world.state(r);
  EXPECT_NEAR(s.pose.x, 100, 0.2);
  EXPECT_NEAR(s.pose.y, 50, 0.2);
  EXPECT_GT(s.pose.theta, 0.1);  // 10 cm/s differential over a 9.4 cm wheelbase: ~0.3 rad
}

TEST(EnkiWorld, InfraredSeesAWallAheadAndNothingOnAnEmptySide) {
  // The wall's face is at x = 69; the robot's front about 8 cm ahead of its centre at x = 55.
  EnkiWorld world(with_wall(vertical_wall(70, 20, 80)), 7);
  const std::size_t facing = world.add_robot("facing", RobotKind::kThymio2, {55, 50, 0});
  const std::size_t away = world.add_robot("away", RobotKind::kThymio2, {150, 50, 0});
  EXPECT_EQ(world.ir(facing), IrReadings{});  // nothing measured before the first step
  world.step(kDt);
  const IrReadings f = world.ir(facing);
  EXPECT_GT(f[2], 2000.0f) << "centre front sensor";
  EXPECT_GT(f[1], 500.0f);
  EXPECT_GT(f[3], 500.0f);
  EXPECT_LT(f[5], 100.0f) << "back sensors see nothing";
  EXPECT_LT(f[6], 100.0f);
  for (float v : world.ir(away)) EXPECT_LT(v, 100.0f);  // open space all round (robots far apart)
  for (float v : f) {
    EXPECT_GE(v, 0.0f);
    EXPECT_LE(v, static_cast<float>(kIrMax));
  }
}

TEST(EnkiWorld, InfraredForgetsAWallOnceTheRobotTurnsAway) {
  // Facing a wall, then turning on the spot until the wall is behind: the front sensors must fall
  // back to (nearly) nothing and the back ones take over. Debian's Enki 1.6.99 keeps the front
  // readings of its Thymio2 stuck near their last value here.
  EnkiWorld world(with_wall(vertical_wall(70, 0, 100)), 7);
  const std::size_t r = world.add_robot("a", RobotKind::kThymio2, {55, 50, 0});
  world.step(kDt);
  EXPECT_GT(world.ir(r)[2], 2000.0f);
  world.set_wheels(r, -5, 5);
  int steps = 0;
  while (std::abs(world.state(r).pose.theta) < 3.0) {
    world.step(kDt);
    ASSERT_LT(++steps, 500) << "the robot did not turn";
  }
  world.set_wheels(r, 0, 0);
  world.step(kDt);
  const IrReadings ir = world.ir(r);
  for (std::size_t i = 0; i < 5; ++i) EXPECT_LT(ir[i], 100.0f) << "front sensor " << i << " sees the wall behind";
  EXPECT_GT(ir[5] + ir[6], 1000.0f) << "the back sensors see it";
}

TEST(EnkiWorld, InfraredGrowsAsTheWallComesCloser) {
  EnkiWorld world(with_wall(vertical_wall(100, 0, 100)), 2);
  const std::size_t r = world.add_robot("a", RobotKind::kThymio2, {60, 50, 0});
  world.set_wheels(r, 5, 5);
  float previous = -1;
  int rising = 0, steps = 0;
  while (world.state(r).pose.x < 88) {
    world.step(kDt);
    const float v = world.ir(r)[2];
    if (v > previous + 10) ++rising;
    previous = v;
    ASSERT_LT(++steps, 1000);
  }
  EXPECT_GT(previous, 3000.0f);
  EXPECT_GT(rising, steps / 3);
}

TEST(EnkiWorld, ContactsWithAnInnerWallAreCounted) {
  EnkiWorld world(with_wall(vertical_wall(100, 20, 80)), 4);
  const std::size_t r = world.add_robot("a", RobotKind::kThymio2, {60, 50, 0});
  world.set_wheels(r, 10, 10);
  std::uint64_t first_contact = 0;
  for (int i = 1; i <= 300; ++i) {
    world.step(kDt);
    if (first_contact == 0 && world.state(r).in_contact) first_contact = static_cast<std::uint64_t>(i);
  }
  const RobotState s = world.state(r);
  ASSERT_GT(first_contact, 0u);
  // Pushing against the wall from first contact on: nearly every step from then is a contact.
  EXPECT_TRUE(s.in_contact);
  EXPECT_GE(s.contact_steps, (300 - first_contact) * 9 / 10);
  EXPECT_LE(s.contact_steps, 300 - first_contact + 1);
  EXPECT_LT(s.pose.x, 99.0) << "the wall stopped it";
  EXPECT_GT(s.pose.x, 85.0);
}

TEST(EnkiWorld, ContactsWithTheArenaSideAreCounted) {
  EnkiWorld world(empty_arena(100, 100), 4);
  const std::size_t r = world.add_robot("a", RobotKind::kThymio2, {50, 50, std::numbers::pi / 2});
  world.set_wheels(r, 12, 12);  // up, towards y = 100
  std::uint64_t first_contact = 0;
  for (int i = 1; i <= 300; ++i) {
    world.step(kDt);
    if (first_contact == 0 && world.state(r).in_contact) first_contact = static_cast<std::uint64_t>(i);
  }
  const RobotState s = world.state(r);
  // The front is about 8 cm ahead of the centre: 42 cm at 12 cm/s, some 117 steps.
  EXPECT_GT(first_contact, 100u);
  EXPECT_LT(first_contact, 130u);
  EXPECT_TRUE(s.in_contact);
  EXPECT_GE(s.contact_steps, (300 - first_contact) * 9 / 10);
  EXPECT_LE(s.contact_steps, 300 - first_contact + 1);
  EXPECT_LT(s.pose.y, 100.0) << "the side holds the robot inside";
  EXPECT_GT(s.pose.y, 85.0);
  EXPECT_EQ(world.wall_objects(), 0u) << "the sides are Enki's square walls";
}

TEST(EnkiWorld, DrivingAlongASideCloseByIsNoContact) {
  EnkiWorld world(empty_arena(200, 100), 4);
  // Thymio2 is about 11 cm wide: 8 cm from the side leaves a 2 to 3 cm gap.
  const std::size_t r = world.add_robot("a", RobotKind::kThymio2, {20, 8, 0});
  world.set_wheels(r, 10, 10);
  for (int i = 0; i < 400; ++i) world.step(kDt);
  const RobotState s = world.state(r);
  EXPECT_GT(s.pose.x, 120.0);
  EXPECT_EQ(s.contact_steps, 0u);
}

TEST(EnkiWorld, RobotsTouchingEachOtherCountAsContact) {
  EnkiWorld world(empty_arena(), 4);
  const std::size_t a = world.add_robot("a", RobotKind::kThymio2, {60, 50, 0});
  const std::size_t b = world.add_robot("b", RobotKind::kThymio2, {100, 50, std::numbers::pi});
  world.set_wheels(a, 10, 10);
  world.set_wheels(b, 10, 10);
  for (int i = 0; i < 200; ++i) world.step(kDt);
  EXPECT_GT(world.state(a).contact_steps, 0u);
  EXPECT_GT(world.state(b).contact_steps, 0u);
}

// --- determinism -------------------------------------------------------------------------------

struct Snapshot {
  std::vector<RobotState> states;
  std::vector<IrReadings> ir;
  bool operator==(const Snapshot& o) const {
    if (states.size() != o.states.size() || ir != o.ir) return false;
    for (std::size_t i = 0; i < states.size(); ++i) {
      const RobotState &a = states[i], &b = o.states[i];
      // Bitwise: determinism means the same doubles, not close ones.
      if (std::memcmp(&a.pose, &b.pose, sizeof(Pose)) != 0 || a.distance != b.distance ||
          a.contact_steps != b.contact_steps || a.in_contact != b.in_contact)
        return false;
    }
    return true;
  }
};

// A maze with a few robots driven by a Braitenberg avoider, so their paths depend on the IR
// readings (noise included) and on collisions.
struct MazeRun {
  explicit MazeRun(std::uint64_t seed) {
    MazeOptions o;
    o.cells = 4;
    o.seed = 11;
    maze = *generate_maze(o);
    world = std::make_unique<EnkiWorld>(maze.world, seed);
  }
  void add_robots(std::size_t n, const std::function<void()>& between = {}) {
    kernel::RandomStream r(5);
    auto starts = *maze.random_starts(n, r);
    for (std::size_t i = 0; i < n; ++i) {
      if (between) between();
      world->add_robot("r" + std::to_string(i), RobotKind::kThymio2, starts[i]);
    }
  }
  void step() {
    for (std::size_t i = 0; i < world->robot_count(); ++i) {
      const IrReadings ir = world->ir(i);
      const double l = (ir[0] + ir[1]) / kIrMax, rr = (ir[3] + ir[4]) / kIrMax, c = ir[2] / kIrMax;
      world->set_wheels(i, 10 - 12 * rr - 8 * c, 10 - 12 * l + 8 * c);
    }
    world->step(kDt);
  }
  Snapshot snapshot() const {
    Snapshot s;
    for (std::size_t i = 0; i < world->robot_count(); ++i) {
      s.states.push_back(world->state(i));
      s.ir.push_back(world->ir(i));
    }
    return s;
  }
  Maze maze;
  std::unique_ptr<EnkiWorld> world;
};

std::vector<Snapshot> run_alone(std::uint64_t seed, int steps) {
  MazeRun run(seed);
  run.add_robots(6);
  std::vector<Snapshot> out;
  for (int i = 0; i < steps; ++i) {
    run.step();
    out.push_back(run.snapshot());
  }
  return out;
}

TEST(EnkiWorld, SameSeedGivesTheSameTrajectoriesAndReadings) {
  const auto a = run_alone(42, 300);
  const auto b = run_alone(42, 300);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) ASSERT_TRUE(a[i] == b[i]) << "step " << i;
  // The robots did move, and something was sensed: the comparison was not of zeros.
  double moved = 0;
  float sensed = 0;
  for (const auto& s : a.back().states) moved += s.distance;
  for (const auto& s : a)
    for (const auto& ir : s.ir)
      for (float v : ir) sensed = std::max(sensed, v);
  EXPECT_GT(moved, 6 * 30.0);
  EXPECT_GT(sensed, 1000.0f);
}

TEST(EnkiWorld, InterleavedWorldsInOneProcessMatchWorldsRunAlone) {
  const auto alone = run_alone(42, 200);
  const auto alone7 = run_alone(7, 200);
  // Two worlds, built and stepped in turn, with heap churn between robot creations: freed holes
  // below the first robot would give later robots lower addresses if Enki objects came from the
  // heap, and so another iteration order.
  std::vector<std::unique_ptr<char[]>> junk;
  auto churn = [&] {
    for (int i = 0; i < 8; ++i) junk.push_back(std::make_unique<char[]>(5000));
    junk.erase(junk.begin(), junk.begin() + 4);
  };
  MazeRun a(42), b(7);
  a.add_robots(6, churn);
  b.add_robots(6, churn);
  for (int i = 0; i < 200; ++i) {
    a.step();
    churn();
    b.step();
    ASSERT_TRUE(a.snapshot() == alone[static_cast<std::size_t>(i)]) << "world a, step " << i;
    ASSERT_TRUE(b.snapshot() == alone7[static_cast<std::size_t>(i)]) << "world b, step " << i;
  }
}

TEST(EnkiWorld, WorldsOnDifferentThreadsMatchWorldsRunAlone) {
  const auto alone = run_alone(42, 150);
  std::vector<std::vector<Snapshot>> got(3);
  std::vector<std::thread> threads;
  for (std::size_t t = 0; t < got.size(); ++t) threads.emplace_back([&, t] { got[t] = run_alone(42, 150); });
  for (auto& t : threads) t.join();
  for (const auto& g : got) {
    ASSERT_EQ(g.size(), alone.size());
    for (std::size_t i = 0; i < g.size(); ++i) ASSERT_TRUE(g[i] == alone[i]) << "step " << i;
  }
}

TEST(EnkiWorld, DifferentSeedsGiveDifferentNoise) {
  // One robot standing before a wall: only noise can make two runs differ.
  auto readings = [](std::uint64_t seed) {
    EnkiWorld world(with_wall(vertical_wall(70, 20, 80)), seed);
    const std::size_t r = world.add_robot("a", RobotKind::kThymio2, {55, 50, 0});
    std::vector<float> v;
    for (int i = 0; i < 20; ++i) {
      world.step(kDt);
      v.push_back(world.ir(r)[1]);
    }
    return v;
  };
  const auto a = readings(1), b = readings(2);
  EXPECT_EQ(a, readings(1));
  EXPECT_NE(a, b);
  // Noise, not a different world: the readings agree to within a few noise deviations (2.87).
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(a[i], b[i], 30.0f);
  // And the noise is drawn afresh every step.
  EXPECT_NE(a[0], a[1]);
}

TEST(EnkiWorld, DifferentSeedsGiveDifferentMotorNoise) {
  auto final_pose = [](std::uint64_t seed) {
    EnkiWorld world(empty_arena(400, 100), seed);
    const std::size_t r = world.add_robot("a", RobotKind::kThymio2, {20, 50, 0});
    world.set_wheels(r, 10, 10);
    for (int i = 0; i < 100; ++i) world.step(kDt);
    return world.state(r).pose;
  };
  const Pose a = final_pose(1), b = final_pose(2), a2 = final_pose(1);
  EXPECT_EQ(a.x, a2.x);
  EXPECT_EQ(a.theta, a2.theta);
  EXPECT_TRUE(a.x != b.x || a.theta != b.theta);
}

// --- bad input ---------------------------------------------------------------------------------

TEST(EnkiWorld, BadSpecsAreRejectedWithTheirLocation) {
  EXPECT_THROW(EnkiWorld(empty_arena(0, 100), 1), std::invalid_argument);
  EXPECT_THROW(EnkiWorld(empty_arena(std::numeric_limits<double>::infinity(), 100), 1), std::invalid_argument);
  WallSpec w = vertical_wall(50, 0, 10);
  w.thickness = -1;
  w.where = {"maze.yaml", 12, 7};
  try {
    EnkiWorld world(with_wall(w), 1);
    FAIL() << "accepted a negative thickness";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("maze.yaml:12:7"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("thickness"), std::string::npos) << e.what();
  }
  w.thickness = 2;
  w.x1 = std::nan("");
  EXPECT_FALSE(EnkiWorld::check_spec(with_wall(w)));
  EXPECT_TRUE(EnkiWorld::check_spec(with_wall(vertical_wall(50, 0, 10))));
}

TEST(EnkiWorld, BadRobotsAndCommandsAreRejected) {
  EnkiWorld world(empty_arena(), 1, {.max_robots = 2});
  EXPECT_THROW(world.add_robot("out", RobotKind::kThymio2, {-1, 50, 0}), std::invalid_argument);
  EXPECT_THROW(world.add_robot("out", RobotKind::kThymio2, {50, 101, 0}), std::invalid_argument);
  EXPECT_THROW(world.add_robot("nan", RobotKind::kThymio2, {50, 50, std::nan("")}), std::invalid_argument);
  EXPECT_EQ(world.robot_count(), 0u);
  const std::size_t r = world.add_robot("a", RobotKind::kThymio2, {50, 50, 0});
  world.add_robot("b", RobotKind::kThymio2, {150, 50, 0});
  EXPECT_THROW(world.add_robot("c", RobotKind::kThymio2, {100, 50, 0}), std::length_error);
  EXPECT_EQ(world.robot_name(r), "a");
  EXPECT_THROW(world.set_wheels(r, std::nan(""), 0), std::invalid_argument);
  EXPECT_THROW(world.set_wheels(7, 1, 1), std::out_of_range);
  EXPECT_THROW((void)world.ir(7), std::out_of_range);
  EXPECT_THROW((void)world.state(2), std::out_of_range);
  EXPECT_THROW(world.step(0), std::invalid_argument);
  EXPECT_THROW(world.step(std::nan("")), std::invalid_argument);
  EXPECT_EQ(world.state(r).left_speed, 0.0);  // the refused command changed nothing
  world.step(kDt);
  EXPECT_EQ(world.steps(), 1u);
}

TEST(EnkiWorld, MazeWallsBecomeObjects) {
  MazeOptions o;
  o.cells = 5;
  const Maze m = *generate_maze(o);
  EnkiWorld world(m.world, 1);
  EXPECT_EQ(world.wall_objects(), m.world.walls.size());
  // A robot at every cell centre fits: nothing touches anything after a step.
  for (std::size_t i = 0; i < m.centres.size(); ++i)
    world.add_robot("r" + std::to_string(i), RobotKind::kThymio2, m.centres[i]);
  world.step(kDt);
  for (std::size_t i = 0; i < world.robot_count(); ++i) EXPECT_FALSE(world.state(i).in_contact) << i;
}

}  // namespace
}  // namespace symb::sim
