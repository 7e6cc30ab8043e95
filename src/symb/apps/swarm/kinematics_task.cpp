#include "symb/apps/swarm/kinematics_task.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "symb/apps/swarm/layouts.hpp"

namespace symb::apps::swarm {

namespace {

constexpr double kPi = std::numbers::pi;

double wrap_angle(double a) {
  a = std::remainder(a, 2 * kPi);
  return a <= -kPi ? a + 2 * kPi : a;
}

}  // namespace

os::TaskType KinematicsTask::type() {
  using P = KinematicsParams;
  os::ParamTable<P> p;
  p.add("arena", &P::arena).range(0.1, 1000.0).doc("side of the square arena, m");
  p.add("radius", &P::radius).range(0.001, 10.0).doc("body radius, m");
  p.add("wheel_base", &P::wheel_base).range(0.01, 10.0).doc("distance between the wheels, m");
  p.add("max_wheel_speed", &P::max_wheel_speed).range(0.0, 10.0).doc("wheel speed limit, m/s");
  p.add("command_timeout", &P::command_timeout)
      .range(0.001, 3600.0)
      .doc("the wheels stop when no command came for this long");
  auto t = os::declare_task_type(
      "kinematics", "differential-drive body in a square walled arena: integrates wheel speeds, sends the pose",
      std::move(p), [](const P& c) -> kernel::Result<std::unique_ptr<KinematicsTask>> {
        if (2 * c.radius >= c.arena)
          return kernel::Error{"a body of radius " + std::to_string(c.radius) + " m does not fit an arena of " +
                               std::to_string(c.arena) + " m"};
        return std::make_unique<KinematicsTask>(c);
      });
  t.defaults.period = std::chrono::milliseconds(10);
  t.defaults.priority = 2;  // the world moves before anyone senses it at the same instant
  t.defaults.queue_capacity = 4;
  return t;
}

KinematicsTask::KinematicsTask(const KinematicsParams& params) : p_(params) {}

void KinematicsTask::on_start() {
  // Where the robot is put down is part of the node's seeded randomness, so a run is repeatable.
  auto& rng = random();
  x_ = rng.uniform(p_.radius, p_.arena - p_.radius);
  y_ = rng.uniform(p_.radius, p_.arena - p_.radius);
  heading_ = rng.uniform(-kPi, kPi);
  last_step_ = now();
  char text[96];
  std::snprintf(text, sizeof text, "put down at (%.3f, %.3f) m heading %.1f deg", x_, y_, heading_ * 180 / kPi);
  log(os::LogLevel::kInfo, text);
  send_pose();
}

void KinematicsTask::on_message(const os::Message& m) {
  const auto v = m.numbers();
  if (v.size() < WheelLayout::kCount) return;  // not a wheel command: someone hooked us to something else
  left_ = std::clamp(static_cast<double>(v[WheelLayout::kLeft]), -p_.max_wheel_speed, p_.max_wheel_speed);
  right_ = std::clamp(static_cast<double>(v[WheelLayout::kRight]), -p_.max_wheel_speed, p_.max_wheel_speed);
  last_command_ = now();
  if (stopped_by_timeout_) {
    stopped_by_timeout_ = false;
    log(os::LogLevel::kInfo, "wheel commands arrive: moving");
  }
}

void KinematicsTask::on_tick() {
  const kernel::Time t = now();
  // The step is measured, not assumed, so the same code integrates correctly on a wall clock
  // that jitters; a long stall (a debugger, a loaded machine) is not turned into a teleport.
  const double dt = std::min(kernel::to_seconds(t - last_step_), 0.1);
  last_step_ = t;
  if (!stopped_by_timeout_ && t - last_command_ > p_.command_timeout) {
    // A controller that died or was suspended must not leave the robot driving blind.
    stopped_by_timeout_ = true;
    left_ = right_ = 0;
    log(os::LogLevel::kWarn, "no wheel command for too long: stopped");
  }
  speed_ = (left_ + right_) / 2;
  turn_rate_ = (right_ - left_) / p_.wheel_base;
  // Midpoint heading: second-order accurate for a constant turn rate, at no extra cost.
  const double mid = heading_ + turn_rate_ * dt / 2;
  double x = x_ + speed_ * std::cos(mid) * dt;
  double y = y_ + speed_ * std::sin(mid) * dt;
  heading_ = wrap_angle(heading_ + turn_rate_ * dt);
  const double lo = p_.radius, hi = p_.arena - p_.radius;
  const char* wall = x < lo ? "west" : x > hi ? "east" : y < lo ? "south" : y > hi ? "north" : nullptr;
  x_ = std::clamp(x, lo, hi);
  y_ = std::clamp(y, lo, hi);
  note_contact(wall != nullptr, wall);
  send_pose();
}

void KinematicsTask::note_contact(bool contact, const char* wall) {
  // Logged on the edge only: a robot pressed against a wall must not flood the log.
  if (contact && !contact_) {
    char text[96];
    std::snprintf(text, sizeof text, "touched the %s wall at (%.3f, %.3f) m", wall, x_, y_);
    log(os::LogLevel::kWarn, text);
  }
  contact_ = contact;
}

void KinematicsTask::send_pose() {
  send(PoseLayout::kPort, {static_cast<float>(x_), static_cast<float>(y_), static_cast<float>(heading_),
                           static_cast<float>(speed_), static_cast<float>(turn_rate_), contact_ ? 1.0f : 0.0f});
}

}  // namespace symb::apps::swarm
