#include "symb/robot/actuator_task.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>

#include "symb/os/node.hpp"

namespace symb::robot {

using kernel::Error;

const char* to_string(OdometryFormat f) { return f == OdometryFormat::kPose ? "pose" : "wheels"; }

namespace {

bool finite_positive(double v) { return std::isfinite(v) && v > 0; }
bool finite_non_negative(double v) { return std::isfinite(v) && v >= 0; }

}  // namespace

ActuatorTask::ActuatorTask(std::shared_ptr<DifferentialDrive> drive, Options options)
    : drive_(std::move(drive)),
      options_(options),
      goal_warning_(options.warn_interval),
      odometry_warning_(options.warn_interval),
      drive_warning_(options.warn_interval) {
  bind_parameters(options_);
  const auto bad = [](const std::string& why) { throw std::invalid_argument("actuator task: " + why); };
  if (!drive_) bad("no drive");
  if (!finite_positive(options_.max_speed)) bad("max_speed must be > 0");
  if (!finite_positive(options_.wheel_base)) bad("wheel_base must be > 0");
  if (!finite_non_negative(options_.kp_distance) || !finite_non_negative(options_.kp_turn) ||
      !finite_non_negative(options_.kp_heading))
    bad("gains must be finite and >= 0");
  if (!finite_positive(options_.distance_tolerance) || !finite_positive(options_.angle_tolerance))
    bad("tolerances must be > 0");
  if (options_.odometry_timeout.count() <= 0) bad("odometry_timeout must be > 0");
  if (options_.odometry_port == options_.command_port) bad("odometry and commands need different ports");
}

kernel::Status ActuatorTask::command(os::Node& node, os::TaskId task, const DriveGoal& goal) {
  os::Message m;
  m.port = kCommandPort;
  m.payload = encode_goal(goal);
  return node.post(task, m, goal.kind == GoalKind::kStop ? os::QueuePolicy::kKeepNewest : os::QueuePolicy::kRefuse);
}

kernel::Status ActuatorTask::stop(os::Node& node, os::TaskId task) { return command(node, task, DriveGoal::stop()); }

ActuatorTaskStats ActuatorTask::stats() const {
  constexpr auto kRelaxed = std::memory_order_relaxed;
  ActuatorTaskStats s;
  s.accepted = accepted_.load();
  s.completed = completed_.load();
  s.aborted = aborted_.load();
  s.rejected = rejected_.load();
  s.timeouts = timeouts_.load();
  s.odometry = odometry_.load();
  s.odometry_rejected = odometry_rejected_.load();
  s.drive_errors = drive_errors_.load();
  s.busy = busy_.load(kRelaxed);
  return s;
}

void ActuatorTask::on_start() {
  if (!drive_->is_open())
    if (auto st = drive_->open(); !st) log(os::LogLevel::kWarn, "cannot open '" + drive_->name() + "': " + st.error());
}

void ActuatorTask::on_stop() {
  // Deleted while driving: hooks are gone, so there is nobody to report to, but the wheels
  // must not keep turning.
  if (goal_) {
    goal_.reset();
    busy_.store(false, std::memory_order_relaxed);
  }
  halt();
}

void ActuatorTask::warn(os::WarningLimiter& limiter, const std::string& text) {
  if (limiter.note(now()))
    log(os::LogLevel::kWarn,
        limiter.count() > 1 ? text + " (" + std::to_string(limiter.count()) + " since last report)" : text);
}

double ActuatorTask::speed_limit() const { return std::min(options_.max_speed, drive_->max_wheel_speed()); }

void ActuatorTask::on_message(const os::Message& m) {
  const bool from_code = !m.source.valid() && m.port == kCommandPort;
  if (m.port == options_.command_port || from_code) return handle_goal(m);
  if (m.port == options_.odometry_port) return handle_odometry(m.numbers());
}

void ActuatorTask::report(GoalEvent event, const DriveGoal& goal, double achieved, GoalReason reason) {
  send(kStatusPort, encode_status({event, goal.id, goal.kind, achieved, reason}));
}

void ActuatorTask::handle_goal(const os::Message& m) {
  auto decoded = decode_goal(m.numbers());
  const auto reject = [&](const DriveGoal& g, const std::string& why) {
    rejected_.bump();
    warn(goal_warning_, "goal rejected: " + why);
    report(GoalEvent::kRejected, g, 0, GoalReason::kBadGoal);
  };
  if (!decoded) {
    DriveGoal unknown;
    // Keep the id when it is readable, so the sender can match the rejection.
    if (m.numbers().size() > 3) {
      const float id = m.numbers()[3];
      if (std::isfinite(id) && id >= 0 && id <= static_cast<float>(kMaxGoalId) && id == std::floor(id))
        unknown.id = static_cast<std::uint32_t>(id);
    }
    return reject(unknown, decoded.error());
  }
  DriveGoal g = *decoded;
  if (g.kind == GoalKind::kStop) {
    if (goal_) return halt_and_finish(GoalEvent::kAborted, GoalReason::kStopped);
    halt();
    return;
  }
  if (g.id == 0) {
    g.id = next_id_;
    next_id_ = next_id_ >= kMaxGoalId ? 1 : next_id_ + 1;
  }
  const double limit = speed_limit();
  char text[128];
  if (g.kind == GoalKind::kHoldSpeed) {
    if (std::abs(g.value) > limit) {
      std::snprintf(text, sizeof text, "hold-speed goal %u: %.3g m/s clamped to the limit %.3g m/s", g.id, g.value,
                    limit);
      warn(goal_warning_, text);
      g.value = std::clamp(g.value, -limit, limit);
    }
  } else {
    if (g.speed <= 0) {
      std::snprintf(text, sizeof text, "%s goal %u needs a speed > 0, got %.3g", to_string(g.kind), g.id, g.speed);
      return reject(g, text);
    }
    if (g.speed > limit) {
      std::snprintf(text, sizeof text, "%s goal %u: speed %.3g m/s clamped to the limit %.3g m/s", to_string(g.kind),
                    g.id, g.speed, limit);
      warn(goal_warning_, text);
      g.speed = limit;
    }
  }
  if (goal_) finish(GoalEvent::kAborted, GoalReason::kReplaced);
  Active a;
  a.goal = g;
  a.accepted_at = now();
  // A pose younger than the timeout is a good start; an older one waits for fresh odometry.
  if (have_pose_ && a.accepted_at - last_odometry_ <= options_.odometry_timeout) {
    a.started = true;
    a.start = pose_;
  }
  goal_ = a;
  busy_.store(true, std::memory_order_relaxed);
  if (!a.started) halt();  // whatever the wheels did before, they wait for a pose now
  accepted_.bump();
  report(GoalEvent::kAccepted, g, 0, GoalReason::kNone);
}

void ActuatorTask::handle_odometry(std::span<const float> v) {
  const std::size_t needed = options_.odometry == OdometryFormat::kPose ? 3 : 2;
  bool ok = v.size() >= needed;
  for (std::size_t i = 0; ok && i < needed; ++i) ok = std::isfinite(v[i]);
  if (!ok) {
    // Not counted as odometry: persistent garbage lets the silence timeout stop the wheels.
    odometry_rejected_.bump();
    warn(odometry_warning_, std::string("odometry rejected: expected ") +
                                (needed == 3 ? "[x, y, theta]" : "[left, right]") + " as finite numbers");
    return;
  }
  if (options_.odometry == OdometryFormat::kPose) {
    const double theta = v[2];
    if (!have_pose_) {
      pose_.theta = theta;
    } else {
      pose_.theta += std::remainder(theta - raw_theta_, 2 * std::numbers::pi);
    }
    raw_theta_ = theta;
    pose_.x = v[0];
    pose_.y = v[1];
  } else {
    const double l = v[0], r = v[1];
    if (have_wheels_) {
      const double dl = l - left_dist_, dr = r - right_dist_;
      const double ds = (dl + dr) / 2, dtheta = (dr - dl) / options_.wheel_base;
      const double mid = pose_.theta + dtheta / 2;
      pose_.x += ds * std::cos(mid);
      pose_.y += ds * std::sin(mid);
      pose_.theta += dtheta;
    }
    left_dist_ = l;
    right_dist_ = r;
    have_wheels_ = true;
  }
  have_pose_ = true;
  last_odometry_ = now();
  odometry_.bump();
  if (goal_ && !goal_->started) {
    goal_->started = true;
    goal_->start = pose_;
  }
}

double ActuatorTask::achieved() const {
  if (!goal_ || !goal_->started) return 0;
  const Pose& s = goal_->start;
  switch (goal_->goal.kind) {
    case GoalKind::kDrive:
    case GoalKind::kHoldSpeed:
      // Along the heading the goal started with: a sideways slip is not progress.
      return (pose_.x - s.x) * std::cos(s.theta) + (pose_.y - s.y) * std::sin(s.theta);
    case GoalKind::kTurn: return pose_.theta - s.theta;
    case GoalKind::kStop: break;
  }
  return 0;
}

void ActuatorTask::finish(GoalEvent event, GoalReason reason) {
  if (!goal_) return;
  const DriveGoal g = goal_->goal;
  const double done = achieved();
  goal_.reset();
  busy_.store(false, std::memory_order_relaxed);
  if (event == GoalEvent::kCompleted) completed_.bump();
  if (event == GoalEvent::kAborted) aborted_.bump();
  report(event, g, done, reason);
}

kernel::Status ActuatorTask::drive_wheels(double left, double right) {
  auto st = drive_->set_wheel_speeds(left, right);
  if (!st) {
    drive_errors_.bump();
    warn(drive_warning_, st.error());
  }
  return st;
}

void ActuatorTask::wheels(double left, double right) {
  // A goal cannot be reached through a drive that refuses commands; the sender may retry.
  if (!drive_wheels(left, right) && goal_) finish(GoalEvent::kAborted, GoalReason::kDriveError);
}

void ActuatorTask::halt_and_finish(GoalEvent event, GoalReason reason) {
  // The wheels are told to stop before the goal's end is counted and reported: whoever hears of
  // it (a hooked task, a thread reading stats()) finds them stopped. A drive that refuses the stop
  // is counted and warned about, but the goal ends for the reason it ended.
  (void)drive_wheels(0, 0);
  finish(event, reason);
}

void ActuatorTask::on_tick() {
  if (!goal_) return;
  const kernel::Time t = now();
  const kernel::Time heard = std::max(last_odometry_, goal_->accepted_at);
  if (t - heard > options_.odometry_timeout) {
    timeouts_.bump();
    char text[128];
    std::snprintf(text, sizeof text, "%s goal %u aborted: no odometry for %.3f s, wheels stopped",
                  to_string(goal_->goal.kind), goal_->goal.id, kernel::to_seconds(t - heard));
    warn(odometry_warning_, text);
    halt_and_finish(GoalEvent::kAborted, GoalReason::kOdometryTimeout);
    return;
  }
  if (!goal_->started) return;  // no pose to measure from yet: the wheels stay as they are (still)
  const DriveGoal& g = goal_->goal;
  const double half_base = options_.wheel_base / 2;
  const double done = achieved();
  double v = 0, u = 0;  // forward speed and the wheels' half difference, m/s
  switch (g.kind) {
    case GoalKind::kDrive: {
      const double rest = g.value - done;
      if (std::abs(rest) <= options_.distance_tolerance) {
        halt_and_finish(GoalEvent::kCompleted, GoalReason::kNone);
        return;
      }
      v = std::clamp(options_.kp_distance * rest, -g.speed, g.speed);
      u = std::clamp(options_.kp_heading * (goal_->start.theta - pose_.theta) * half_base, -g.speed, g.speed);
      break;
    }
    case GoalKind::kTurn: {
      const double rest = g.value - done;
      if (std::abs(rest) <= options_.angle_tolerance) {
        halt_and_finish(GoalEvent::kCompleted, GoalReason::kNone);
        return;
      }
      u = std::clamp(options_.kp_turn * rest * half_base, -g.speed, g.speed);
      break;
    }
    case GoalKind::kHoldSpeed: {
      v = g.value;
      const double room = std::abs(v);
      u = std::clamp(options_.kp_heading * (goal_->start.theta - pose_.theta) * half_base, -room, room);
      break;
    }
    case GoalKind::kStop: break;
  }
  double left = v - u, right = v + u;
  // Scale both wheels together: the robot keeps the curve it was asked for, only slower.
  const double limit = speed_limit();
  const double top = std::max(std::abs(left), std::abs(right));
  if (top > limit) {
    left *= limit / top;
    right *= limit / top;
  }
  wheels(left, right);
}

kernel::Status ActuatorTask::on_parameter_changed(std::string_view name) {
  if (name == "warn_interval") {
    goal_warning_.set_interval(options_.warn_interval);
    odometry_warning_.set_interval(options_.warn_interval);
    drive_warning_.set_interval(options_.warn_interval);
  }
  return {};
}

}  // namespace symb::robot
