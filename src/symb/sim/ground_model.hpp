// GroundModel: Thymio II's two ground sensors, which look down just behind the front edge and see
// the floor's reflectance: 1 on the plain floor, a zone's `ground` value over a marked zone
// (WorldSpec::zones). It is geometry only, independent of the physics backend, so any World gets
// ground readings from its spec and a robot's pose. No noise: a marked zone is meant to be found.
#pragma once

#include <array>
#include <cstddef>

#include "symb/sim/world_spec.hpp"

namespace symb::sim {

inline constexpr std::size_t kGroundCount = 2;  // 0 left, 1 right
using GroundReadings = std::array<float, kGroundCount>;

// Where the sensors sit on the robot (cm, robot frame: x forward, y left), as on Thymio II.
inline constexpr double kGroundSensorX = 7.2;
inline constexpr double kGroundSensorY = 1.15;

// The floor's reflectance at a point: the last zone containing it, or 1.
float floor_reflectance(const WorldSpec& world, double x, double y);

// Both sensors' readings for a robot at `pose`.
GroundReadings ground_readings(const WorldSpec& world, const Pose& pose);

}  // namespace symb::sim
