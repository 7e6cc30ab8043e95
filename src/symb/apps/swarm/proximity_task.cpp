#include "symb/apps/swarm/proximity_task.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "symb/apps/swarm/layouts.hpp"

namespace symb::apps::swarm {

os::TaskType ProximityTask::type() {
  os::ParamTable<ProximityParams> p;
  p.add("arena", &ProximityParams::arena).range(0.1, 1000.0).doc("side of the square arena, m");
  p.add("range", &ProximityParams::range).range(0.01, 100.0).doc("farthest distance sensed, m").live();
  p.add("noise", &ProximityParams::noise).range(0.0, 1.0).doc("standard deviation of the reading, m").live();
  auto t = os::declare_task_type(
      "proximity", "four-ray range sensor (front, left, back, right) against the walls of a square arena", std::move(p),
      [](const ProximityParams& c) { return std::make_unique<ProximityTask>(c); });
  t.defaults.period = std::chrono::milliseconds(30);
  t.defaults.priority = 1;
  // Only the newest pose matters to a sensor.
  t.defaults.queue_capacity = 2;
  return t;
}

void ProximityTask::on_message(const os::Message& m) {
  const auto v = m.numbers();
  if (v.size() < PoseLayout::kCount) return;
  x_ = v[PoseLayout::kX];
  y_ = v[PoseLayout::kY];
  heading_ = v[PoseLayout::kHeading];
  have_pose_ = true;
}

double ProximityTask::ray(double angle) const {
  // Distance from (x, y) along `angle` to the first wall of [0, arena]^2.
  const double c = std::cos(angle), s = std::sin(angle);
  double d = std::numeric_limits<double>::infinity();
  if (c > 1e-12) d = std::min(d, (p_.arena - x_) / c);
  if (c < -1e-12) d = std::min(d, -x_ / c);
  if (s > 1e-12) d = std::min(d, (p_.arena - y_) / s);
  if (s < -1e-12) d = std::min(d, -y_ / s);
  return std::max(d, 0.0);
}

void ProximityTask::on_tick() {
  if (!have_pose_) return;  // nothing to measure against before the body reported in
  constexpr double kQuarter = std::numbers::pi / 2;
  float out[ProximityLayout::kCount];
  const std::size_t slots[] = {ProximityLayout::kFront, ProximityLayout::kLeft, ProximityLayout::kBack,
                               ProximityLayout::kRight};
  auto& rng = random();
  for (int k = 0; k < 4; ++k) {
    double d = ray(heading_ + k * kQuarter);
    if (p_.noise > 0) d += p_.noise * rng.normal();
    out[slots[k]] = static_cast<float>(std::clamp(d, 0.0, p_.range));
  }
  out[ProximityLayout::kRange] = static_cast<float>(p_.range);
  send(ProximityLayout::kPort, std::span<const float>(out));
}

}  // namespace symb::apps::swarm
