// WanderTask ("wander"): the swarm demo's controller, a Braitenberg-style random walker. On each
// proximity reading (ProximityLayout) it slows down for what is ahead, turns away from the nearer
// side, adds a random turn from its own random stream, and sends wheel speeds (WheelLayout). It
// keeps no map and no plan: all it knows arrives in the latest message.
#pragma once

#include "symb/os/task.hpp"
#include "symb/os/task_type_registry.hpp"

namespace symb::apps::swarm {

struct WanderParams {
  double speed = 0.25;      // cruising speed, m/s
  double turn_noise = 2.0;  // standard deviation of the random turn, rad/s
  double avoid_gain = 6.0;  // turn rate for an obstacle at zero distance, rad/s
  double wheel_base = 0.1;  // m
};

class WanderTask final : public os::Task {
 public:
  explicit WanderTask(const WanderParams& params) : p_(params) { bind_parameters(p_); }

  // The registry entry: parameters speed, turn_noise, avoid_gain, wheel_base; event-driven (no
  // period).
  static os::TaskType type();

 protected:
  void on_message(const os::Message& message) override;

 private:
  WanderParams p_;  // speed, turn_noise and avoid_gain change at runtime
  bool avoiding_ = false;
};

}  // namespace symb::apps::swarm
