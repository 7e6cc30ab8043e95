#include "symb/apps/swarm/kinematics_task.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>

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
  os::TaskType t;
  t.name = "kinematics";
  t.doc = "differential-drive body in a square walled arena: integrates wheel speeds, sends the pose";
  t.params = {
      {"arena", os::ParamType::kReal, 4.0, 0.1, 1000.0, "side of the square arena, m"},
      {"radius", os::ParamType::kReal, 0.05, 0.001, 10.0, "body radius, m"},
      {"wheel_base", os::ParamType::kReal, 0.1, 0.01, 10.0, "distance between the wheels, m"},
      {"max_wheel_speed", os::ParamType::kReal, 0.5, 0.0, 10.0, "wheel speed limit, m/s"},
      {"command_timeout", os::ParamType::kDuration, kernel::Duration{std::chrono::milliseconds(200)}, 0.001, 3600.0,
       "the wheels stop when no command came for this long"},
  };
  t.defaults.period = std::chrono::milliseconds(10);
  t.defaults.priority = 2;  // the world moves before anyone senses it at the same instant
  t.defaults.queue_capacity = 4;
  t.make = [](const os::ParamSet& p) { return std::make_unique<KinematicsTask>(p); };
  return t;
}

KinematicsTask::KinematicsTask(const os::ParamSet& p)
    : arena_(p.real("arena")),
      radius_(p.real("radius")),
      wheel_base_(p.real("wheel_base")),
      max_wheel_speed_(p.real("max_wheel_speed")),
      command_timeout_(p.duration("command_timeout")) {
  if (2 * radius_ >= arena_)
    throw std::invalid_argument("a body of radius " + std::to_string(radius_) + " m does not fit an arena of " +
                                std::to_string(arena_) + " m");
}

void KinematicsTask::on_start() {
  // Where the robot is put down is part of the node's seeded randomness, so a run is repeatable.
  auto& rng = random();
  x_ = rng.uniform(radius_, arena_ - radius_);
  y_ = rng.uniform(radius_, arena_ - radius_);
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
  left_ = std::clamp(static_cast<double>(v[WheelLayout::kLeft]), -max_wheel_speed_, max_wheel_speed_);
  right_ = std::clamp(static_cast<double>(v[WheelLayout::kRight]), -max_wheel_speed_, max_wheel_speed_);
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
  if (!stopped_by_timeout_ && t - last_command_ > command_timeout_) {
    // A controller that died or was suspended must not leave the robot driving blind.
    stopped_by_timeout_ = true;
    left_ = right_ = 0;
    log(os::LogLevel::kWarn, "no wheel command for too long: stopped");
  }
  speed_ = (left_ + right_) / 2;
  turn_rate_ = (right_ - left_) / wheel_base_;
  // Midpoint heading: second-order accurate for a constant turn rate, at no extra cost.
  const double mid = heading_ + turn_rate_ * dt / 2;
  double x = x_ + speed_ * std::cos(mid) * dt;
  double y = y_ + speed_ * std::sin(mid) * dt;
  heading_ = wrap_angle(heading_ + turn_rate_ * dt);
  const double lo = radius_, hi = arena_ - radius_;
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
