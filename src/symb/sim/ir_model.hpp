// IrModel: Thymio II's 7 horizontal IR proximity sensors, computed geometrically. Enki 1.6.99
// (Debian's libenki-dev) has a Thymio2 whose IR readings go stale: once a sensor has seen a wall,
// it keeps reporting it (about 3,700) after the robot has turned away, even facing open space
// (reproduced with a bare Enki program: one wall, one Thymio2 turned in place). A controller fed
// that data sees walls everywhere and stalls. So the Enki backend keeps Enki for what it does well
// (bodies, wheels, collisions) and computes the IR readings here, with Enki's own sensor model:
//  - sensor placement and orientation of Enki's Thymio2 (5 front, 2 rear, 3.4 cm high);
//  - three rays per sensor, 15 degrees apart, 14 cm long;
//  - response F(x) = m (c - x0^2) / (x^2 - 2 x0 x + c) with m = 4505, x0 = 0.03, c = 73, 0 beyond
//    range; combined as F(d_left) + F(d_centre) + F(d_right) - 2 F(d_centre / cos 15deg);
//  - Gaussian noise, sd 2.87, from the world's own random stream; clamped to [0, 4505].
// Obstacles are wall rectangles and other robots (circles of the Thymio's half width). Each read
// first keeps the wall edges and robots near enough to be seen by any of its 21 rays, found on two
// spatial grids (spatial_grid.hpp): the walls' edges, built once, and the robots' positions, built
// by set_robots() (about 10 ns a robot). So a reading costs about the same in a maze of 1,000
// walls as in an empty box, and grows with what is near the robot, not with the swarm (at 4,000
// cm^2 a robot: about 0.5 us among 1,000 robots, 0.7 us among 10,000, where the cache misses).
// Leaving out what cannot be hit changes no reading: each ray keeps the nearest hit, and nothing
// left out is within its reach.
//
// Use: set_robots(poses) once after the bodies move, then read(i, noise) for each robot. read() is
// const and keeps no scratch in the model, so several threads may read different robots at once
// (each with its own noise stream); set_robots() must not run concurrently with reads.
#pragma once

#include <span>
#include <vector>

#include "symb/kernel/random_stream.hpp"
#include "symb/robot/thymio_ir.hpp"
#include "symb/sim/spatial_grid.hpp"
#include "symb/sim/world.hpp"
#include "symb/sim/world_spec.hpp"

namespace symb::sim {

class IrModel {
 public:
  struct Rect {
    double cx, cy, half_length, half_width, angle;
  };
  // Walls as rectangles centred on (cx, cy), `angle` along their length.
  explicit IrModel(std::vector<Rect> walls);
  // A 2D world's walls as every backend builds them: first the arena's four sides (10 cm thick,
  // just outside the arena, closing the corners), then each inner wall of the spec, in order, its
  // segment's length plus its thickness long (capped ends, so walls meeting at a corner leave no
  // gap) and `thickness` wide.
  static std::vector<Rect> walls_of(const WorldSpec& spec);

  // The robots the following reads see: robot i at robots[i] (copied). Their grid is rebuilt.
  void set_robots(std::span<const Pose> robots);
  // Readings of robot `self` (of the last set_robots()) among the others and the walls; draws 7
  // normals from `noise`, one per sensor in order. Throws std::out_of_range for a bad index.
  IrReadings read(std::size_t self, kernel::RandomStream& noise) const;

  static constexpr double kRange = robot::thymio::kIrRange;  // cm
  static constexpr double kRobotRadius = 5.5;                // cm, as seen by another robot's sensors

 private:
  // Without member initialisers: a read's stack buffers of them are not zeroed first.
  struct Segment {
    double x1, y1, x2, y2;
  };
  struct Point {
    double x, y;
  };
  // Distance to the nearest obstacle along (ux, uy) from (px, py); above kRange when none.
  static double ray(double px, double py, double ux, double uy, std::span<const Segment> edges,
                    std::span<const Point> robots);

  std::vector<Segment> edges_;  // of every wall, 4 per wall
  SpatialGrid edge_grid_;       // edges_ by their bounding boxes
  std::vector<Pose> robots_;    // of the last set_robots()
  SpatialGrid robot_grid_;      // robots_ by position
};

}  // namespace symb::sim
