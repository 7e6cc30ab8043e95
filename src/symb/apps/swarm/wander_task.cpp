#include "symb/apps/swarm/wander_task.hpp"

#include <algorithm>

#include "symb/apps/swarm/layouts.hpp"

namespace symb::apps::swarm {

os::TaskType WanderTask::type() {
  os::TaskType t;
  t.name = "wander";
  t.doc = "random walk that turns away from near walls; proximity readings in, wheel speeds out";
  t.params = {
      {"speed", os::ParamType::kReal, 0.25, 0.0, 5.0, "cruising speed, m/s"},
      {"turn_noise", os::ParamType::kReal, 2.0, 0.0, 10.0, "standard deviation of the random turn, rad/s"},
      {"avoid_gain", os::ParamType::kReal, 6.0, 0.0, 100.0, "turn rate for an obstacle at zero distance, rad/s"},
      {"wheel_base", os::ParamType::kReal, 0.1, 0.01, 10.0, "distance between the wheels, m"},
  };
  t.defaults.priority = 1;
  t.defaults.queue_capacity = 2;
  t.make = [](const os::ParamSet& p) { return std::make_unique<WanderTask>(p); };
  return t;
}

WanderTask::WanderTask(const os::ParamSet& p)
    : speed_(p.real("speed")),
      turn_noise_(p.real("turn_noise")),
      avoid_gain_(p.real("avoid_gain")),
      wheel_base_(p.real("wheel_base")) {}

kernel::Status WanderTask::on_parameter(std::string_view name, const os::ParamValue& value) {
  if (name == "speed")
    speed_ = std::get<double>(value);
  else if (name == "turn_noise")
    turn_noise_ = std::get<double>(value);
  else if (name == "avoid_gain")
    avoid_gain_ = std::get<double>(value);
  else
    return os::Task::on_parameter(name, value);
  return {};
}

void WanderTask::on_message(const os::Message& m) {
  const auto v = m.numbers();
  if (v.size() < ProximityLayout::kCount) return;
  const double range = v[ProximityLayout::kRange];
  if (range <= 0) return;
  // Activation 0 (nothing within range) .. 1 (touching).
  const auto near = [&](std::size_t k) { return std::clamp(1.0 - v[k] / range, 0.0, 1.0); };
  const double front = near(ProximityLayout::kFront);
  const double left = near(ProximityLayout::kLeft);
  const double right = near(ProximityLayout::kRight);

  // Something ahead: turn towards the side with more room, harder the closer it is.
  const double escape = left > right ? -1.0 : 1.0;
  const double turn = avoid_gain_ * ((right - left) + escape * front) + turn_noise_ * random().normal();
  const double forward = speed_ * (1.0 - front);

  // Logged once per encounter: the hysteresis keeps sensor noise near the threshold from
  // reporting one wall many times.
  if (!avoiding_ && front > 0.3) {
    avoiding_ = true;
    log(os::LogLevel::kInfo, escape > 0 ? "wall ahead: turning left" : "wall ahead: turning right");
  } else if (avoiding_ && front < 0.1) {
    avoiding_ = false;
  }

  const double half = turn * wheel_base_ / 2;
  send(WheelLayout::kPort, {static_cast<float>(forward - half), static_cast<float>(forward + half)});
}

}  // namespace symb::apps::swarm
