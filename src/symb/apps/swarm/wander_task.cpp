#include "symb/apps/swarm/wander_task.hpp"

#include <algorithm>

#include "symb/apps/swarm/layouts.hpp"

namespace symb::apps::swarm {

os::TaskType WanderTask::type() {
  os::ParamTable<WanderParams> p;
  p.add("speed", &WanderParams::speed).range(0.0, 5.0).doc("cruising speed, m/s").live();
  p.add("turn_noise", &WanderParams::turn_noise)
      .range(0.0, 10.0)
      .doc("standard deviation of the random turn, rad/s")
      .live();
  p.add("avoid_gain", &WanderParams::avoid_gain)
      .range(0.0, 100.0)
      .doc("turn rate for an obstacle at zero distance, rad/s")
      .live();
  p.add("wheel_base", &WanderParams::wheel_base).range(0.01, 10.0).doc("distance between the wheels, m");
  auto t = os::declare_task_type("wander",
                                 "random walk that turns away from near walls; proximity readings in, wheel speeds out",
                                 std::move(p), [](const WanderParams& c) { return std::make_unique<WanderTask>(c); });
  t.defaults.priority = 1;
  t.defaults.queue_capacity = 2;
  return t;
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
  const double turn = p_.avoid_gain * ((right - left) + escape * front) + p_.turn_noise * random().normal();
  const double forward = p_.speed * (1.0 - front);

  // Logged once per encounter: the hysteresis keeps sensor noise near the threshold from
  // reporting one wall many times.
  if (!avoiding_ && front > 0.3) {
    avoiding_ = true;
    log(os::LogLevel::kInfo, escape > 0 ? "wall ahead: turning left" : "wall ahead: turning right");
  } else if (avoiding_ && front < 0.1) {
    avoiding_ = false;
  }

  const double half = turn * p_.wheel_base / 2;
  send(WheelLayout::kPort, {static_cast<float>(forward - half), static_cast<float>(forward + half)});
}

}  // namespace symb::apps::swarm
