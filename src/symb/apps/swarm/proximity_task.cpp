#include "symb/apps/swarm/proximity_task.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "symb/apps/swarm/layouts.hpp"

namespace symb::apps::swarm {

os::TaskType ProximityTask::type() {
  os::TaskType t;
  t.name = "proximity";
  t.doc = "four-ray range sensor (front, left, back, right) against the walls of a square arena";
  t.params = {
      {"arena", os::ParamType::kReal, 4.0, 0.1, 1000.0, "side of the square arena, m"},
      {"range", os::ParamType::kReal, 0.5, 0.01, 100.0, "farthest distance sensed, m"},
      {"noise", os::ParamType::kReal, 0.005, 0.0, 1.0, "standard deviation of the reading, m"},
  };
  t.defaults.period = std::chrono::milliseconds(30);
  t.defaults.priority = 1;
  // Only the newest pose matters to a sensor.
  t.defaults.queue_capacity = 2;
  t.make = [](const os::ParamSet& p) { return std::make_unique<ProximityTask>(p); };
  return t;
}

ProximityTask::ProximityTask(const os::ParamSet& p)
    : arena_(p.real("arena")), range_(p.real("range")), noise_(p.real("noise")) {}

kernel::Status ProximityTask::on_parameter(std::string_view name, const os::ParamValue& value) {
  if (name == "range")
    range_ = std::get<double>(value);
  else if (name == "noise")
    noise_ = std::get<double>(value);
  else
    return os::Task::on_parameter(name, value);
  return {};
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
  if (c > 1e-12) d = std::min(d, (arena_ - x_) / c);
  if (c < -1e-12) d = std::min(d, -x_ / c);
  if (s > 1e-12) d = std::min(d, (arena_ - y_) / s);
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
    if (noise_ > 0) d += noise_ * rng.normal();
    out[slots[k]] = static_cast<float>(std::clamp(d, 0.0, range_));
  }
  out[ProximityLayout::kRange] = static_cast<float>(range_);
  send(ProximityLayout::kPort, std::span<const float>(out));
}

}  // namespace symb::apps::swarm
