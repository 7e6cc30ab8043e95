// ActuatorTask: the paper's ActuatorTask, an actuator with a task of its own that is "activated to
// reach a given value or to perform a task" and "may be hooked to different sensors to perform
// its goal": the low-level controllers of SymbricatorRTOS. This one drives a differential-drive
// base towards goals (drive a distance, turn an angle, hold a speed; see drive_goal.hpp) using
// odometry that a hooked sensor task sends it.
//
// Design:
//  - Inputs are messages, told apart by port: odometry on `odometry_port` (kDataPort), goals on
//    `command_port` (kCommandPort). Code outside any task commands it by handle through the
//    static command()/stop(), which post the same goal messages: every goal is handled on the
//    task's own context, in order, under either executor. Hook the odometry source keep-newest
//    and goal senders refuse-when-full (a lost goal is worse than a late one).
//  - Odometry is either a pose [x, y, theta] (m, m, rad) or cumulative wheel distances
//    [left, right] (m) integrated with `wheel_base`. Heading is unwrapped, so a turn goal of
//    3 pi means one and a half turns.
//  - At its period the task runs one step of a proportional controller: forward speed from the
//    remaining distance (kp_distance, 1/s), turn rate from the remaining angle (kp_turn, 1/s)
//    and a heading hold while driving straight (kp_heading, 1/s), limited to the goal's speed
//    and the drive's limit (both wheels scaled together, so the curve keeps its shape).
//  - A goal completes when within tolerance; the wheels stop (0, 0) and a status is sent on
//    kStatusPort. A new goal replaces the one in progress (status: aborted, replaced) without a
//    stop in between. A stop goal, the odometry falling silent for `odometry_timeout` while a
//    goal runs, and the task being deleted all stop the wheels; a goal never runs blind.
//  - Bad goals (NaN, unknown kind, a non-positive speed) are rejected with a status and a log
//    line, and the goal in progress goes on; a speed above the limit is clamped with a warning.
//  - Known limit: a task has no suspend handler, so a suspended ActuatorTask leaves the wheels
//    as they were; stop it before suspending it.
#pragma once

#include <atomic>
#include <memory>
#include <optional>
#include <string_view>

#include "symb/kernel/counter.hpp"
#include "symb/kernel/result.hpp"
#include "symb/os/ids.hpp"
#include "symb/os/task.hpp"
#include "symb/os/warning_limiter.hpp"
#include "symb/robot/differential_drive.hpp"
#include "symb/robot/drive_goal.hpp"
#include "symb/robot/ports.hpp"

namespace symb::os {
class Node;
}

namespace symb::robot {

enum class OdometryFormat : std::uint8_t { kPose, kWheelDistances };

const char* to_string(OdometryFormat f);

struct ActuatorTaskStats {
  std::uint64_t accepted = 0;
  std::uint64_t completed = 0;
  std::uint64_t aborted = 0;   // replaced, stopped or timed out
  std::uint64_t rejected = 0;  // bad goals
  std::uint64_t timeouts = 0;  // goals aborted because odometry fell silent
  std::uint64_t odometry = 0;  // odometry messages used
  std::uint64_t odometry_rejected = 0;
  std::uint64_t drive_errors = 0;  // commands the drive refused
  bool busy = false;               // a goal is in progress
};

class ActuatorTask : public os::Task {
 public:
  struct Options {
    double max_speed = 0.3;             // m/s per wheel, also bounded by the drive's own limit
    double kp_distance = 2.0;           // 1/s: forward speed per metre still to go
    double kp_turn = 4.0;               // 1/s: turn rate per radian still to turn
    double kp_heading = 4.0;            // 1/s: turn rate per radian off the heading while driving
    double distance_tolerance = 0.005;  // m
    double angle_tolerance = 0.01;      // rad
    kernel::Duration odometry_timeout = std::chrono::milliseconds(200);
    OdometryFormat odometry = OdometryFormat::kPose;
    double wheel_base = 0.1;  // m, between the wheels' contact points
    os::Port odometry_port = kDataPort;
    os::Port command_port = kCommandPort;
    kernel::Duration warn_interval = std::chrono::seconds(1);
  };

  // Throws std::invalid_argument on a missing drive or options that make no sense (a
  // non-positive wheel base or speed, negative gains, one port for both inputs).
  explicit ActuatorTask(std::shared_ptr<DifferentialDrive> drive) : ActuatorTask(std::move(drive), Options{}) {}
  ActuatorTask(std::shared_ptr<DifferentialDrive> drive, Options options);

  // From code, by handle: posts `goal` to the ActuatorTask `task` of `node` (from any thread).
  static kernel::Status command(os::Node& node, os::TaskId task, const DriveGoal& goal);
  // Halts the wheels and aborts the goal in progress. Never refused for a full queue: it
  // pushes out the oldest queued message instead.
  static kernel::Status stop(os::Node& node, os::TaskId task);

  // Safe from any thread.
  ActuatorTaskStats stats() const;

 protected:
  void on_start() override;
  void on_message(const os::Message& m) override;
  void on_tick() override;
  void on_stop() override;
  kernel::Status on_parameter_changed(std::string_view name) override;

 private:
  struct Pose {
    double x = 0, y = 0, theta = 0;  // theta unwrapped
  };
  struct Active {
    DriveGoal goal;
    kernel::Time accepted_at{0};
    bool started = false;  // `start` holds the pose the goal is measured from
    Pose start;
  };

  void handle_goal(const os::Message& m);
  void handle_odometry(std::span<const float> v);
  void finish(GoalEvent event, GoalReason reason);
  void halt_and_finish(GoalEvent event, GoalReason reason);
  void report(GoalEvent event, const DriveGoal& goal, double achieved, GoalReason reason);
  double achieved() const;
  void wheels(double left, double right);
  kernel::Status drive_wheels(double left, double right);
  void halt() { wheels(0, 0); }
  double speed_limit() const;
  void warn(os::WarningLimiter& limiter, const std::string& text);

  std::shared_ptr<DifferentialDrive> drive_;
  Options options_;
  std::optional<Active> goal_;
  std::uint32_t next_id_ = 1;
  bool have_pose_ = false;
  Pose pose_;
  double raw_theta_ = 0;  // pose odometry: the last heading as sent, for unwrapping
  double left_dist_ = 0, right_dist_ = 0;
  bool have_wheels_ = false;
  kernel::Time last_odometry_{0};
  os::WarningLimiter goal_warning_;
  os::WarningLimiter odometry_warning_;
  os::WarningLimiter drive_warning_;
  kernel::Counter accepted_, completed_, aborted_, rejected_, timeouts_, odometry_, odometry_rejected_,
      drive_errors_;  // kernel/counter.hpp
  std::atomic<bool> busy_{false};
};

}  // namespace symb::robot
