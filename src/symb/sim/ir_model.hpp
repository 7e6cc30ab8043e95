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
// first keeps the walls and robots near enough to be seen by any of its 21 rays, so a reading costs
// about the same in a maze of 1,000 walls as in an empty box.
#pragma once

#include <span>
#include <vector>

#include "symb/kernel/random_stream.hpp"
#include "symb/robot/thymio_ir.hpp"
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

  // Readings of the robot at `self` among robots at `others` (self excluded by index).
  IrReadings read(std::size_t self, std::span<const Pose> robots, kernel::RandomStream& noise) const;

  static constexpr double kRange = robot::thymio::kIrRange;  // cm
  static constexpr double kRobotRadius = 5.5;                // cm, as seen by another robot's sensors

 private:
  // Distance to the nearest obstacle along (ux, uy) from (px, py); above kRange when none.
  double ray(double px, double py, double ux, double uy) const;

  struct Segment {
    double x1, y1, x2, y2;
  };
  struct Wall {
    double cx, cy, reach;  // bounding circle
    Segment edges[4];
  };
  std::vector<Wall> walls_;
  // Scratch of read(): what its rays can reach (mutable: reused to avoid allocating per reading).
  mutable std::vector<Segment> near_edges_;
  mutable std::vector<Pose> near_robots_;
};

}  // namespace symb::sim
