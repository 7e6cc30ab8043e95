// Box2DWorld on its own: motion from the wheels, walls, sides and robots stopping it, contacts,
// IR, bad input, determinism and the parallel IR reads. Its agreement with Enki in the shipped
// mazes is box2d_agreement_test.cpp.
#include "symb/sim/box2d/box2d_world.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <functional>
#include <limits>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "symb/kernel/parallel_for.hpp"
#include "symb/sim/maze_generator.hpp"

namespace symb::sim {
namespace box2d_world_test {
namespace {

constexpr double kStep = 0.03;

WorldSpec arena(double w = 200, double h = 100) {
  WorldSpec s;
  s.engine = Engine2d::kBox2d;
  s.width = w;
  s.height = h;
  return s;
}

WallSpec upright_wall(double x, double y1, double y2) {
  WallSpec w;
  w.x1 = w.x2 = x;
  w.y1 = y1;
  w.y2 = y2;
  w.thickness = 2;
  return w;
}

void run(World& world, int steps) {
  for (int i = 0; i < steps; ++i) world.step(kStep);
}

// Two threads: the second half of the range on a thread of its own.
class TwoThreads final : public kernel::ParallelFor {
 public:
  unsigned threads() const override { return 2; }
  void run(std::size_t n, const std::function<void(std::size_t, std::size_t)>& fn) override {
    const std::size_t mid = n / 2;
    std::exception_ptr error;
    std::thread other([&] {
      try {
        if (mid < n) fn(mid, n);
      } catch (...) {
        error = std::current_exception();
      }
    });
    if (mid > 0) fn(0, mid);
    other.join();
    if (error) std::rethrow_exception(error);
    ++runs;
  }
  int runs = 0;
};

TEST(Box2DWorld, DrivingStraightReachesTheCommandedSpeed) {
  Box2DWorld world(arena(), 1);
  const std::size_t r = world.add_robot("a", RobotKind::kThymio2, {20, 50, 0});
  world.set_wheels(r, 10, 10);
  // As in Enki, a command acts from the step after the next one.
  world.step(kStep);
  EXPECT_EQ(world.state(r).pose.x, 20);
  world.step(kStep);
  EXPECT_NEAR(world.state(r).pose.x, 20.3, 0.01);
  run(world, 99);  // 3 s at 10 cm/s; the motor noise (+-2.7% per step) averages out
  const RobotState s = world.state(r);
  EXPECT_NEAR(s.pose.x, 50, 0.3);
  EXPECT_NEAR(s.pose.y, 50, 0.3);
  EXPECT_NEAR(s.distance, 30, 0.3);
  EXPECT_NEAR(world.time(), 3.03, 1e-9);
  EXPECT_EQ(world.steps(), 101u);
  EXPECT_EQ(s.contact_steps, 0u);
  EXPECT_FALSE(s.in_contact);
}

TEST(Box2DWorld, WheelSpeedsAreClampedToTheThymioLimit) {
  Box2DWorld world(arena(400, 100), 1);
  const std::size_t r = world.add_robot("a", RobotKind::kThymio2, {20, 50, 0});
  world.set_wheels(r, 100, 1e9);
  EXPECT_DOUBLE_EQ(world.state(r).left_speed, kMaxWheelSpeed);
  EXPECT_DOUBLE_EQ(world.state(r).right_speed, kMaxWheelSpeed);
  run(world, 100);
  EXPECT_NEAR(world.state(r).distance, 3 * kMaxWheelSpeed, 0.5);
  world.set_wheels(r, -100, -100);
  EXPECT_DOUBLE_EQ(world.state(r).left_speed, -kMaxWheelSpeed);
}

TEST(Box2DWorld, TurningOnTheSpotKeepsThePosition) {
  Box2DWorld world(arena(), 3);
  const std::size_t r = world.add_robot("a", RobotKind::kThymio2, {100, 50, 0});
  world.set_wheels(r, -5, 5);  // counter-clockwise: 10 cm/s over a 9.4 cm axle, 1.064 rad/s
  run(world, 10);
  const RobotState s = world.state(r);
  EXPECT_NEAR(s.pose.x, 100, 0.01);
  EXPECT_NEAR(s.pose.y, 50, 0.01);
  EXPECT_NEAR(s.pose.theta, 0.27 * 10 / 9.4, 0.01);  // 9 steps of turning: the first step waits
  run(world, 1000);                                  // 30 s: several turns; the heading stays in (-pi, pi]
  EXPECT_GT(world.state(r).pose.theta, -std::numbers::pi);
  EXPECT_LE(world.state(r).pose.theta, std::numbers::pi);
  EXPECT_NEAR(world.state(r).pose.x, 100, 0.05);
}

TEST(Box2DWorld, AWallStopsTheRobotAndCountsContactSteps) {
  WorldSpec spec = arena();
  spec.walls.push_back(upright_wall(100, 0, 100));  // its face at x = 99
  Box2DWorld world(spec, 1);
  const std::size_t r = world.add_robot("a", RobotKind::kThymio2, {70, 50, 0});
  world.set_wheels(r, 10, 10);
  run(world, 200);  // 6 s: 21 cm to the wall (the hull reaches 8 cm ahead), then pushing
  const RobotState s = world.state(r);
  EXPECT_NEAR(s.pose.x, 91, 0.2);  // the front arc on the wall's face
  EXPECT_TRUE(s.in_contact);
  // About 70 steps to reach the wall, then in contact for the rest.
  EXPECT_GT(s.contact_steps, 120u);
  EXPECT_LT(s.contact_steps, 135u);
  EXPECT_NEAR(s.distance, 21, 0.5);  // pushing does not add distance
  // Backing away ends the contact: one more step pushing (the command acts a step later), then
  // the first step back leaves the face.
  world.set_wheels(r, -10, -10);
  run(world, 10);
  EXPECT_FALSE(world.state(r).in_contact);
  EXPECT_EQ(world.state(r).contact_steps, s.contact_steps + 1);
}

TEST(Box2DWorld, TheArenaSidesStopRobotsToo) {
  Box2DWorld world(arena(), 1);
  const std::size_t right = world.add_robot("right", RobotKind::kThymio2, {170, 50, 0});
  const std::size_t down = world.add_robot("down", RobotKind::kThymio2, {50, 30, -std::numbers::pi / 2});
  const std::size_t back = world.add_robot("back", RobotKind::kThymio2, {100, 80, -std::numbers::pi / 2});
  world.set_wheels(right, 10, 10);
  world.set_wheels(down, 10, 10);
  world.set_wheels(back, -10, -10);  // backing up: the flat back, 3 cm behind the axle
  run(world, 200);
  EXPECT_NEAR(world.state(right).pose.x, 192, 0.2);
  EXPECT_NEAR(world.state(down).pose.y, 8, 0.2);
  EXPECT_NEAR(world.state(back).pose.y, 97, 0.2);
  for (const std::size_t r : {right, down, back}) {
    EXPECT_TRUE(world.state(r).in_contact) << r;
    EXPECT_GT(world.state(r).contact_steps, 0u) << r;
  }
}

TEST(Box2DWorld, RobotsThatMeetAreBothInContact) {
  Box2DWorld world(arena(), 1);
  const std::size_t a = world.add_robot("a", RobotKind::kThymio2, {60, 50, 0});
  const std::size_t b = world.add_robot("b", RobotKind::kThymio2, {140, 50, std::numbers::pi});
  const std::size_t idle = world.add_robot("idle", RobotKind::kThymio2, {100, 85, 0});
  world.set_wheels(a, 10, 10);
  world.set_wheels(b, 10, 10);
  // They meet nose to nose after (80 - 16) / 20 = 3.2 s, about step 107.
  int first = 0;
  for (int i = 1; i <= 150 && first == 0; ++i) {
    world.step(kStep);
    if (world.state(a).in_contact) first = i;
  }
  EXPECT_GT(first, 100);
  EXPECT_LT(first, 112);
  const RobotState sa = world.state(a), sb = world.state(b);
  EXPECT_TRUE(sb.in_contact);
  EXPECT_NEAR(sb.pose.x - sa.pose.x, 16, 0.3);  // front arcs touching: 8 cm each
  EXPECT_NEAR((sa.pose.x + sb.pose.x) / 2, 100, 1.0);
  EXPECT_EQ(world.state(idle).contact_steps, 0u);
  // IR: each sees the other straight ahead; the idle robot sees nothing.
  EXPECT_GT(world.ir(a)[2], 1000.0f);
  EXPECT_GT(world.ir(b)[2], 1000.0f);
  EXPECT_LT(world.ir(idle)[2], 100.0f);
  // Pushing on, nose against round nose without friction, they slide off each other sideways
  // (as two discs would) but never pass through: centres stay 11 cm (two half widths) apart.
  for (int i = 0; i < 150; ++i) {
    world.step(kStep);
    const Pose pa = world.state(a).pose, pb = world.state(b).pose;
    ASSERT_GT(std::hypot(pb.x - pa.x, pb.y - pa.y), 10.9) << i;
  }
  EXPECT_GT(world.state(a).contact_steps, 20u);
  EXPECT_EQ(world.state(a).contact_steps, world.state(b).contact_steps);
}

TEST(Box2DWorld, ThePushedRobotStopsWhenThePushEnds) {
  Box2DWorld world(arena(), 1);
  const std::size_t pusher = world.add_robot("pusher", RobotKind::kThymio2, {40, 50, 0});
  const std::size_t pushed = world.add_robot("pushed", RobotKind::kThymio2, {70, 50, 0});
  world.set_wheels(pusher, 10, 10);
  run(world, 150);  // contact after ~1.5 s, then 3 s of pushing
  EXPECT_GT(world.state(pushed).pose.x, 75);
  world.set_wheels(pusher, 0, 0);
  world.step(kStep);
  const double x = world.state(pushed).pose.x;
  run(world, 30);
  EXPECT_NEAR(world.state(pushed).pose.x, x, 0.01);
}

TEST(Box2DWorld, IrSeesAWallAhead) {
  WorldSpec spec = arena();
  spec.walls.push_back(upright_wall(100, 0, 100));
  Box2DWorld world(spec, 1);
  const std::size_t near = world.add_robot("near", RobotKind::kThymio2, {85, 50, 0});
  const std::size_t far = world.add_robot("far", RobotKind::kThymio2, {40, 50, 0});
  EXPECT_EQ(world.ir(near)[2], 0.0f);  // before the first step
  world.step(kStep);
  EXPECT_GT(world.ir(near)[2], 1000.0f);
  EXPECT_LT(world.ir(near)[5], 100.0f);  // the back sensors face away
  EXPECT_LT(world.ir(far)[2], 100.0f);
}

TEST(Box2DWorld, RefusesBadInputWithAReason) {
  auto message = [](const std::function<void()>& f) -> std::string {
    try {
      f();
    } catch (const std::exception& e) {
      return e.what();
    }
    return "";
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  WorldSpec bad = arena();
  bad.width = nan;
  EXPECT_NE(message([&] { Box2DWorld w(bad, 1); }).find("arena"), std::string::npos);
  bad = arena();
  bad.wall_height = 0;
  EXPECT_FALSE(Box2DWorld::check_spec(bad).ok());
  bad = arena();
  WallSpec w = upright_wall(50, 0, 50);
  w.thickness = 0;
  w.where = {"m.yaml", 12, 7};
  bad.walls.push_back(w);
  const std::string why = message([&] { Box2DWorld b(bad, 1); });
  EXPECT_NE(why.find("m.yaml:12:7"), std::string::npos) << why;
  EXPECT_NE(why.find("thickness"), std::string::npos) << why;
  bad.walls[0].thickness = 2;
  bad.walls[0].x2 = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(Box2DWorld::check_spec(bad).ok());

  Box2DWorld world(arena(), 1);
  EXPECT_THROW(world.add_robot("x", RobotKind::kThymio2, {-1, 50, 0}), std::invalid_argument);
  EXPECT_THROW(world.add_robot("x", RobotKind::kThymio2, {50, 101, 0}), std::invalid_argument);
  EXPECT_THROW(world.add_robot("x", RobotKind::kThymio2, {nan, 50, 0}), std::invalid_argument);
  EXPECT_THROW(world.add_robot("x", RobotKind::kThymio2, {50, 50, nan}), std::invalid_argument);
  EXPECT_EQ(world.robot_count(), 0u);
  const std::size_t r = world.add_robot("a", RobotKind::kThymio2, {50, 50, 0});
  EXPECT_THROW(world.set_wheels(r, nan, 1), std::invalid_argument);
  EXPECT_THROW(world.set_wheels(r, 1, nan), std::invalid_argument);
  EXPECT_EQ(world.state(r).left_speed, 0);
  EXPECT_THROW(world.set_wheels(1, 1, 1), std::out_of_range);
  EXPECT_THROW(world.state(1), std::out_of_range);
  EXPECT_THROW(world.ir(1), std::out_of_range);
  EXPECT_THROW(world.robot_name(1), std::out_of_range);
  EXPECT_THROW(world.step(0), std::invalid_argument);
  EXPECT_THROW(world.step(-0.03), std::invalid_argument);
  EXPECT_THROW(world.step(1.5), std::invalid_argument);
  EXPECT_THROW(world.step(nan), std::invalid_argument);
  EXPECT_EQ(world.steps(), 0u);
  EXPECT_EQ(world.robot_name(r), "a");
}

// A maze with robots driven by a Braitenberg avoider, so their paths depend on the IR readings
// (and their noise) as well as on the physics.
struct Box2DSwarm {
  Box2DSwarm(std::uint64_t seed, std::size_t n, kernel::ParallelFor* parallel = nullptr) {
    MazeOptions o;
    o.cells = 5;
    maze = *generate_maze(o);
    maze.world.engine = Engine2d::kBox2d;
    world = std::make_unique<Box2DWorld>(maze.world, seed);
    world->set_parallel(parallel);
    kernel::RandomStream r(seed, 7);
    auto starts = maze.random_starts(n, r);
    EXPECT_TRUE(starts.ok());
    if (!starts.ok()) return;
    const std::vector<Pose> poses = std::move(starts).value();
    for (const Pose& p : poses) world->add_robot("r", RobotKind::kThymio2, p);
  }
  // ahead: every step begun right after the one before, as the world runner does it.
  void run(int steps, bool ahead = false) {
    for (int s = 0; s < steps; ++s) {
      for (std::size_t i = 0; i < world->robot_count(); ++i) {
        const IrReadings ir = world->ir(i);
        const double left = (ir[0] + ir[1]) / kIrMax, right = (ir[3] + ir[4]) / kIrMax;
        world->set_wheels(i, 12 - 14 * right - 6 * ir[2] / kIrMax, 12 - 14 * left);
      }
      world->step(kStep);
      if (ahead) world->begin_next_step(kStep);
    }
  }
  Maze maze;
  std::unique_ptr<Box2DWorld> world;
};

bool same_bits(const RobotState& a, const RobotState& b) {
  return std::memcmp(&a.pose, &b.pose, sizeof a.pose) == 0 && a.distance == b.distance &&
         a.contact_steps == b.contact_steps && a.in_contact == b.in_contact;
}

TEST(Box2DWorld, SameSeedSameRunBitForBit) {
  Box2DSwarm a(5, 12), b(5, 12), c(6, 12);
  a.run(500);
  b.run(500);
  c.run(500);
  bool differs = false;
  std::uint64_t contacts = 0;
  for (std::size_t i = 0; i < 12; ++i) {
    EXPECT_TRUE(same_bits(a.world->state(i), b.world->state(i))) << i;
    EXPECT_EQ(std::memcmp(a.world->ir(i).data(), b.world->ir(i).data(), sizeof(IrReadings)), 0) << i;
    differs = differs || !same_bits(a.world->state(i), c.world->state(i));
    contacts += a.world->state(i).contact_steps;
  }
  EXPECT_TRUE(differs);  // another seed, another run
  std::printf("box2d swarm: %llu contact steps among 12 robots in 15 s\n", static_cast<unsigned long long>(contacts));
}

TEST(Box2DWorld, SteppingAheadGivesTheSameRunBitForBit) {
  Box2DSwarm whole(4, 16), ahead(4, 16);
  ASSERT_TRUE(ahead.world->can_step_ahead());
  // Commands change every step (the avoider reads the IR): a step that moved with a command set a
  // step too late or too early would part the runs within a few steps.
  whole.run(400);
  ahead.run(400, true);
  std::uint64_t contacts = 0;
  for (std::size_t i = 0; i < 16; ++i) {
    EXPECT_TRUE(same_bits(whole.world->state(i), ahead.world->state(i))) << i;
    EXPECT_EQ(std::memcmp(whole.world->ir(i).data(), ahead.world->ir(i).data(), sizeof(IrReadings)), 0) << i;
    contacts += whole.world->state(i).contact_steps;
  }
  EXPECT_EQ(whole.world->steps(), ahead.world->steps());
  EXPECT_DOUBLE_EQ(whole.world->time(), ahead.world->time());
  // Begun, a step shows nothing yet: state and IR are the last step's until step() finishes it.
  const RobotState before = ahead.world->state(3);
  const IrReadings ir_before = ahead.world->ir(3);
  ahead.world->set_wheels(3, 15, -15);
  ahead.world->begin_next_step(kStep);  // begun already: nothing more happens
  EXPECT_TRUE(same_bits(before, ahead.world->state(3)));
  EXPECT_EQ(std::memcmp(ir_before.data(), ahead.world->ir(3).data(), sizeof(IrReadings)), 0);
  // A finished step of another length than the begun one is refused, and the begun one stays.
  EXPECT_THROW(ahead.world->step(kStep / 2), std::invalid_argument);
  EXPECT_THROW(ahead.world->begin_next_step(0), std::invalid_argument);
  whole.world->set_wheels(3, 15, -15);
  whole.world->step(kStep);
  ahead.world->step(kStep);
  EXPECT_TRUE(same_bits(whole.world->state(3), ahead.world->state(3)));
  std::printf("box2d step ahead: %llu contact steps among 16 robots in 12 s\n",
              static_cast<unsigned long long>(contacts));
}

TEST(Box2DWorld, ParallelIrReadsGiveTheSameBitsAsSerialOnes) {
  TwoThreads two;
  Box2DSwarm serial(9, 20), parallel(9, 20, &two);
  serial.run(300);
  parallel.run(300);
  EXPECT_EQ(two.runs, 300);  // every step's IR went through the threads
  for (std::size_t i = 0; i < 20; ++i) {
    EXPECT_TRUE(same_bits(serial.world->state(i), parallel.world->state(i))) << i;
    EXPECT_EQ(std::memcmp(serial.world->ir(i).data(), parallel.world->ir(i).data(), sizeof(IrReadings)), 0) << i;
  }
}

TEST(Box2DWorld, WorldsOnDifferentThreadsStayIndependent) {
  Box2DSwarm alone(11, 8);
  alone.run(200);
  Box2DSwarm x(11, 8), y(12, 8);
  std::thread tx([&] { x.run(200); });
  std::thread ty([&] { y.run(200); });
  tx.join();
  ty.join();
  for (std::size_t i = 0; i < 8; ++i) EXPECT_TRUE(same_bits(alone.world->state(i), x.world->state(i))) << i;
}

}  // namespace
}  // namespace box2d_world_test
}  // namespace symb::sim
