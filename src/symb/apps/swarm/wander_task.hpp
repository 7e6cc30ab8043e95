// WanderTask ("wander"): the swarm demo's controller, a Braitenberg-style random walker. On each
// proximity reading (ProximityLayout) it slows down for what is ahead, turns away from the nearer
// side, adds a random turn from its own random stream, and sends wheel speeds (WheelLayout). It
// keeps no map and no plan: all it knows arrives in the latest message.
#pragma once

#include "symb/os/task.hpp"
#include "symb/os/task_type_registry.hpp"

namespace symb::apps::swarm {

class WanderTask final : public os::Task {
 public:
  explicit WanderTask(const os::ParamSet& params);

  // The registry entry: parameters speed, turn_noise, avoid_gain, wheel_base; event-driven (no
  // period).
  static os::TaskType type();

 protected:
  void on_message(const os::Message& message) override;
  kernel::Status on_parameter(std::string_view name, const os::ParamValue& value) override;

 private:
  double speed_;
  double turn_noise_;
  double avoid_gain_;
  const double wheel_base_;
  bool avoiding_ = false;
};

}  // namespace symb::apps::swarm
