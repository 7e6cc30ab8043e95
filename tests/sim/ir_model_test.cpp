// IrModel on its spatial grids against a brute-force oracle: the same model culling by a linear
// scan of every wall (bounding circle) and every robot, kept here as it was before the grids.
// Random worlds with walls and crowds of robots, some outside the arena: the readings (noise
// included) must be bit-identical, robot by robot.
#include "symb/sim/ir_model.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <iterator>
#include <limits>
#include <stdexcept>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "symb/kernel/random_stream.hpp"
#include "symb/robot/thymio_ir.hpp"

namespace symb::sim {
namespace ir_model_test {

namespace thymio = robot::thymio;

// The linear-culling IrModel, line for line: the oracle.
class LinearIrModel {
 public:
  explicit LinearIrModel(const std::vector<IrModel::Rect>& walls) {
    for (const IrModel::Rect& r : walls) {
      const double c = std::cos(r.angle), s = std::sin(r.angle);
      const double lx = c * r.half_length, ly = s * r.half_length;
      const double wx = -s * r.half_width, wy = c * r.half_width;
      const double xs[4] = {r.cx + lx + wx, r.cx - lx + wx, r.cx - lx - wx, r.cx + lx - wx};
      const double ys[4] = {r.cy + ly + wy, r.cy - ly + wy, r.cy - ly - wy, r.cy + ly - wy};
      Wall w{r.cx, r.cy, std::hypot(r.half_length, r.half_width), {}};
      for (int i = 0; i < 4; ++i) w.edges[i] = {xs[i], ys[i], xs[(i + 1) % 4], ys[(i + 1) % 4]};
      walls_.push_back(w);
    }
  }

  IrReadings read(std::size_t self, const std::vector<Pose>& robots, kernel::RandomStream& noise) {
    constexpr double kRange = IrModel::kRange, kMountReach = 8.0, kAperture = 15.0 * M_PI / 180.0;
    const Pose& p = robots[self];
    near_edges_.clear();
    for (const Wall& w : walls_) {
      const double reach = w.reach + kRange + 1 + kMountReach;
      const double dx = w.cx - p.x, dy = w.cy - p.y;
      if (dx * dx + dy * dy <= reach * reach)
        near_edges_.insert(near_edges_.end(), std::begin(w.edges), std::end(w.edges));
    }
    near_robots_.clear();
    const double robot_reach = IrModel::kRobotRadius + kRange + 1 + kMountReach;
    for (std::size_t j = 0; j < robots.size(); ++j) {
      const double dx = robots[j].x - p.x, dy = robots[j].y - p.y;
      if (j != self && dx * dx + dy * dy <= robot_reach * robot_reach) near_robots_.push_back(robots[j]);
    }
    const double c = std::cos(p.theta), s = std::sin(p.theta);
    IrReadings out{};
    for (std::size_t i = 0; i < kIrCount; ++i) {
      const thymio::IrMount& m = thymio::kIrMounts[i];
      const double sx = p.x + c * m.x - s * m.y, sy = p.y + s * m.x + c * m.y;
      double d[3];
      for (int k = 0; k < 3; ++k) {
        const double a = m.angle + (1 - k) * kAperture;
        const double rc = std::cos(a), rs = std::sin(a);
        d[k] = ray(sx, sy, c * rc - s * rs, s * rc + c * rs);
      }
      double v = thymio::ir_reading(d[0]) + thymio::ir_reading(d[1]) + thymio::ir_reading(d[2]) -
                 2 * thymio::ir_reading(d[1] / std::cos(kAperture));
      v = std::clamp(v + noise.normal(0, 2.87), 0.0, thymio::kIrMax);
      out[i] = static_cast<float>(v);
    }
    return out;
  }

 private:
  struct Segment {
    double x1, y1, x2, y2;
  };
  struct Wall {
    double cx, cy, reach;
    Segment edges[4];
  };

  static double hit_segment(double px, double py, double ux, double uy, const Segment& e, double limit) {
    const double ex = e.x2 - e.x1, ey = e.y2 - e.y1;
    const double denom = ux * ey - uy * ex;
    if (std::fabs(denom) < 1e-12) return limit;
    const double wx = e.x1 - px, wy = e.y1 - py;
    const double t = (wx * ey - wy * ex) / denom;
    const double s = (wx * uy - wy * ux) / denom;
    if (t < 0 || t > limit || s < 0 || s > 1) return limit;
    return t;
  }

  double ray(double px, double py, double ux, double uy) const {
    double best = IrModel::kRange + 1;
    for (const Segment& e : near_edges_) best = std::min(best, hit_segment(px, py, ux, uy, e, best));
    for (const Pose& robot : near_robots_) {
      const double dx = robot.x - px, dy = robot.y - py;
      const double along = dx * ux + dy * uy;
      const double across2 = dx * dx + dy * dy - along * along;
      const double r2 = IrModel::kRobotRadius * IrModel::kRobotRadius;
      if (across2 > r2) continue;
      const double t = along - std::sqrt(r2 - across2);
      if (t >= 0 && t < best)
        best = t;
      else if (t < 0 && along + std::sqrt(r2 - across2) >= 0)
        best = 0;
    }
    return best;
  }

  std::vector<Wall> walls_;
  std::vector<Segment> near_edges_;
  std::vector<Pose> near_robots_;
};

struct RandomWorld {
  std::vector<IrModel::Rect> walls;
  std::vector<Pose> robots;
};

// An arena of `side` cm with its four sides (as EnkiWorld gives them to the model), `walls` inner
// walls at any angle, and `robots` robots: half spread out, half in tight clusters (so that rays
// hit robots, and sensors sit inside other robots), a few just outside the arena.
RandomWorld random_world(kernel::RandomStream& rng, double side, std::size_t walls, std::size_t robots) {
  RandomWorld w;
  const double t = 10;
  w.walls.push_back({side / 2, -t / 2, side / 2 + t, t / 2, 0});
  w.walls.push_back({side / 2, side + t / 2, side / 2 + t, t / 2, 0});
  w.walls.push_back({-t / 2, side / 2, t / 2, side / 2 + t, 0});
  w.walls.push_back({side + t / 2, side / 2, t / 2, side / 2 + t, 0});
  for (std::size_t i = 0; i < walls; ++i) {
    const double length = rng.uniform(5, side / 3), thickness = rng.uniform(1, 6);
    const double angle = rng.below(2) == 0 ? rng.uniform(-M_PI, M_PI) : (M_PI / 2) * static_cast<double>(rng.below(4));
    w.walls.push_back({rng.uniform(0, side), rng.uniform(0, side), (length + thickness) / 2, thickness / 2, angle});
  }
  while (w.robots.size() < robots) {
    const double theta = rng.uniform(-M_PI, M_PI);
    if (w.robots.size() % 2 == 0 || w.robots.empty()) {
      w.robots.push_back({rng.uniform(-20, side + 20), rng.uniform(-20, side + 20), theta});
    } else {
      const Pose& near = w.robots[rng.below(w.robots.size())];
      w.robots.push_back({near.x + rng.uniform(-15, 15), near.y + rng.uniform(-15, 15), theta});
    }
  }
  return w;
}

TEST(IrModelGrid, ReadsBitForBitAsTheLinearOracleOnRandomWorlds) {
  kernel::RandomStream rng(17, 2);
  std::size_t seen_wall = 0, seen_robot_only = 0, readings = 0;
#ifdef SYMB_SANITIZER
  constexpr int kWorlds = 8;  // the sanitizer builds look for memory errors and races, not numbers
#else
  constexpr int kWorlds = 40;
#endif
  for (int world = 0; world < kWorlds; ++world) {
    const double side = rng.uniform(60, 1500);
    const std::size_t walls = rng.below(60), robots = 2 + rng.below(400);
    const RandomWorld w = random_world(rng, side, walls, robots);
    LinearIrModel oracle(w.walls);
    IrModel model(w.walls);
    model.set_robots(w.robots);
    IrModel walls_only(w.walls);  // to tell readings caused by robots from those caused by walls
    walls_only.set_robots(std::vector<Pose>(1, Pose{}));
    kernel::RandomStream oracle_noise(world, 9), noise(world, 9);
    for (std::size_t i = 0; i < w.robots.size(); ++i) {
      const IrReadings expected = oracle.read(i, w.robots, oracle_noise);
      const IrReadings got = model.read(i, noise);
      ASSERT_EQ(got, expected) << "world " << world << " robot " << i;
      // What the readings saw, without noise: so the comparison above is not one of empty worlds.
      kernel::RandomStream quiet_a(1, 1), quiet_b(1, 1);
      walls_only.set_robots(std::vector<Pose>{w.robots[i]});
      const IrReadings wall_part = walls_only.read(0, quiet_a);
      const IrReadings all = oracle.read(i, w.robots, quiet_b);
      readings += kIrCount;
      for (std::size_t k = 0; k < kIrCount; ++k) {
        if (wall_part[k] > 100) ++seen_wall;
        if (wall_part[k] < 20 && all[k] > 100) ++seen_robot_only;
      }
    }
    // Equal worlds read again after a new set_robots: the grid is rebuilt, not appended to.
    model.set_robots(w.robots);
    kernel::RandomStream again_a(world, 10), again_b(world, 10);
    ASSERT_EQ(model.read(w.robots.size() - 1, again_a), oracle.read(w.robots.size() - 1, w.robots, again_b));
  }
  // Both kinds of obstacle were in sight often enough for the equality to mean something.
  EXPECT_GT(seen_wall, readings / 100);
  EXPECT_GT(seen_robot_only, readings / 100);
}

TEST(IrModelGrid, RobotsFarOutsideTheWallsAndNonFinitePosesReadAsTheOracle) {
  const std::vector<IrModel::Rect> walls = {{50, 50, 30, 1, 0.3}, {0, 0, 5, 5, 0}};
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  // Two robots far from everything but close together, one NaN, one infinite, one by the wall.
  const std::vector<Pose> robots = {{5000, -3000, 0}, {5012, -3000, M_PI}, {nan, 10, 0},
                                    {inf, -inf, 1},   {50, 44, M_PI / 2},  {-1e6, 1e6, 0}};
  LinearIrModel oracle(walls);
  IrModel model(walls);
  model.set_robots(robots);
  kernel::RandomStream a(3, 3), b(3, 3);
  for (std::size_t i = 0; i < robots.size(); ++i) {
    ASSERT_EQ(model.read(i, a), oracle.read(i, robots, b)) << i;
  }
  // The two far robots face each other 12 cm apart: they see each other.
  kernel::RandomStream quiet(4, 4);
  EXPECT_GT(model.read(0, quiet)[2], 1000.0f);
  EXPECT_THROW((void)model.read(robots.size(), quiet), std::out_of_range);
}

TEST(IrModelGrid, ReadsOfDifferentRobotsAreIndependentOfTheirOrder) {
  // read() keeps no scratch: robot i's reading with its own stream is the same whatever was read
  // before (what lets a world read robots on several threads, a stream per robot).
  kernel::RandomStream rng(5, 5);
  const RandomWorld w = random_world(rng, 400, 20, 120);
  IrModel model(w.walls);
  model.set_robots(w.robots);
  std::vector<IrReadings> forward, backward(w.robots.size());
  for (std::size_t i = 0; i < w.robots.size(); ++i) {
    kernel::RandomStream noise(7, i);
    forward.push_back(model.read(i, noise));
  }
  for (std::size_t i = w.robots.size(); i-- > 0;) {
    kernel::RandomStream noise(7, i);
    backward[i] = model.read(i, noise);
  }
  EXPECT_EQ(forward, backward);
}

TEST(IrModelGrid, ReadsOnSeveralThreadsAtOnceEqualReadsOnOne) {
  // What a world with parallel sensing does: set_robots() once, then robots read on several
  // threads, each robot with its own noise stream.
  kernel::RandomStream rng(6, 6);
  const RandomWorld w = random_world(rng, 800, 30, 600);
  IrModel model(w.walls);
  model.set_robots(w.robots);
  std::vector<IrReadings> serial(w.robots.size()), parallel(w.robots.size());
  for (std::size_t i = 0; i < w.robots.size(); ++i) {
    kernel::RandomStream noise(8, i);
    serial[i] = model.read(i, noise);
  }
  constexpr std::size_t kThreads = 4;
  std::vector<std::thread> threads;
  for (std::size_t t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t] {
      for (std::size_t i = t; i < w.robots.size(); i += kThreads) {
        kernel::RandomStream noise(8, i);
        parallel[i] = model.read(i, noise);
      }
    });
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(parallel, serial);
}

}  // namespace ir_model_test
}  // namespace symb::sim
