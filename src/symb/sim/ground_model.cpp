#include "symb/sim/ground_model.hpp"

#include <cmath>

namespace symb::sim {

float floor_reflectance(const WorldSpec& world, double x, double y) {
  for (std::size_t i = world.zones.size(); i-- > 0;)
    if (world.zones[i].contains(x, y)) return static_cast<float>(world.zones[i].ground);
  return 1.0f;
}

GroundReadings ground_readings(const WorldSpec& world, const Pose& pose) {
  if (world.zones.empty()) return {1.0f, 1.0f};  // the common case, without trigonometry
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  GroundReadings out{};
  for (std::size_t i = 0; i < kGroundCount; ++i) {
    const double side = i == 0 ? kGroundSensorY : -kGroundSensorY;
    out[i] = floor_reflectance(world, pose.x + c * kGroundSensorX - s * side, pose.y + s * kGroundSensorX + c * side);
  }
  return out;
}

}  // namespace symb::sim
