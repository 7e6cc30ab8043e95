// DriveGoal and GoalStatus: the message protocol of a drive ActuatorTask. A goal is what a
// low-level controller works towards on its own ("drive 1 m", "turn 90 degrees", "hold 0.2 m/s");
// a status is what it reports back. Both travel as a few numbers inside an ordinary message, so a
// controller of any kind (MDL2e, a neural network, a genome-built task graph, the shell's post)
// can command a drive without knowing anything but this encoding:
//
//   goal   (kCommandPort): [kind, value, speed, id]   id optional (0 or absent: the task picks one)
//     kind 0 stop        -                             halt now, abort any goal
//     kind 1 drive       value = distance, m (signed)  speed = top wheel speed, m/s (> 0)
//     kind 2 turn        value = angle, rad (signed, counter-clockwise positive; may exceed 2 pi)
//                                                      speed = top wheel speed, m/s (> 0)
//     kind 3 hold speed  value = speed, m/s (signed)   never completes; replace it or stop
//   status (kStatusPort):  [event, id, kind, achieved, reason]
//     event 1 accepted, 2 completed, 3 aborted, 4 rejected
//     achieved: distance (m) or angle (rad) covered towards the goal when the event happened
//     reason 0 none, 1 replaced by a newer goal, 2 stop command, 3 odometry silent too long,
//            4 bad goal (the text is in the log), 5 drive refused commands
//
// Ids are whole numbers below 2^24 so a float carries them exactly.
#pragma once

#include <cstdint>
#include <optional>
#include <span>

#include "symb/kernel/result.hpp"
#include "symb/os/message.hpp"

namespace symb::robot {

enum class GoalKind : std::uint8_t { kStop = 0, kDrive = 1, kTurn = 2, kHoldSpeed = 3 };
enum class GoalEvent : std::uint8_t { kAccepted = 1, kCompleted = 2, kAborted = 3, kRejected = 4 };
enum class GoalReason : std::uint8_t {
  kNone = 0,
  kReplaced = 1,
  kStopped = 2,
  kOdometryTimeout = 3,
  kBadGoal = 4,
  kDriveError = 5,
};

const char* to_string(GoalKind k);
const char* to_string(GoalEvent e);
const char* to_string(GoalReason r);

inline constexpr std::uint32_t kMaxGoalId = (1u << 24) - 1;

struct DriveGoal {
  GoalKind kind = GoalKind::kStop;
  double value = 0;
  double speed = 0;
  std::uint32_t id = 0;  // 0: let the task number it

  static DriveGoal stop() { return {}; }
  static DriveGoal drive(double distance, double speed, std::uint32_t id = 0) {
    return {GoalKind::kDrive, distance, speed, id};
  }
  static DriveGoal turn(double angle, double speed, std::uint32_t id = 0) {
    return {GoalKind::kTurn, angle, speed, id};
  }
  static DriveGoal hold_speed(double speed, std::uint32_t id = 0) { return {GoalKind::kHoldSpeed, speed, 0, id}; }
};

struct GoalStatus {
  GoalEvent event = GoalEvent::kAccepted;
  std::uint32_t id = 0;
  GoalKind kind = GoalKind::kStop;
  double achieved = 0;
  GoalReason reason = GoalReason::kNone;
};

os::Payload encode_goal(const DriveGoal& g);
// Checks the shape only (a known kind, finite numbers, a whole id in range); what a goal asks
// for (a speed above the drive's limit) is the task's to judge.
kernel::Result<DriveGoal> decode_goal(std::span<const float> v);

os::Payload encode_status(const GoalStatus& s);
std::optional<GoalStatus> decode_status(std::span<const float> v);

}  // namespace symb::robot
