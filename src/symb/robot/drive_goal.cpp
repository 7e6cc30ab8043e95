#include "symb/robot/drive_goal.hpp"

#include <cmath>
#include <string>

namespace symb::robot {

using kernel::Error;

const char* to_string(GoalKind k) {
  switch (k) {
    case GoalKind::kStop: return "stop";
    case GoalKind::kDrive: return "drive";
    case GoalKind::kTurn: return "turn";
    case GoalKind::kHoldSpeed: return "hold-speed";
  }
  return "?";
}

const char* to_string(GoalEvent e) {
  switch (e) {
    case GoalEvent::kAccepted: return "accepted";
    case GoalEvent::kCompleted: return "completed";
    case GoalEvent::kAborted: return "aborted";
    case GoalEvent::kRejected: return "rejected";
  }
  return "?";
}

const char* to_string(GoalReason r) {
  switch (r) {
    case GoalReason::kNone: return "none";
    case GoalReason::kReplaced: return "replaced";
    case GoalReason::kStopped: return "stopped";
    case GoalReason::kOdometryTimeout: return "odometry-timeout";
    case GoalReason::kBadGoal: return "bad-goal";
    case GoalReason::kDriveError: return "drive-error";
  }
  return "?";
}

os::Payload encode_goal(const DriveGoal& g) {
  return os::Payload{static_cast<float>(g.kind), static_cast<float>(g.value), static_cast<float>(g.speed),
                     static_cast<float>(g.id)};
}

namespace {

// A whole number in [lo, hi], or nothing.
std::optional<std::uint32_t> whole(float v, std::uint32_t lo, std::uint32_t hi) {
  if (!std::isfinite(v) || v != std::floor(v) || v < static_cast<float>(lo) || v > static_cast<float>(hi))
    return std::nullopt;
  return static_cast<std::uint32_t>(v);
}

}  // namespace

kernel::Result<DriveGoal> decode_goal(std::span<const float> v) {
  if (v.empty()) return Error{"empty goal: expected [kind, value, speed, id]"};
  const auto kind = whole(v[0], 0, 3);
  if (!kind) return Error{"unknown goal kind " + std::to_string(v[0]) + " (0 stop, 1 drive, 2 turn, 3 hold speed)"};
  DriveGoal g;
  g.kind = static_cast<GoalKind>(*kind);
  const std::size_t needed = g.kind == GoalKind::kStop ? 1 : g.kind == GoalKind::kHoldSpeed ? 2 : 3;
  if (v.size() < needed)
    return Error{std::string(to_string(g.kind)) + " goal needs " + std::to_string(needed) + " numbers, got " +
                 std::to_string(v.size())};
  if (v.size() > 1) g.value = v[1];
  if (v.size() > 2) g.speed = v[2];
  if (!std::isfinite(g.value) || !std::isfinite(g.speed))
    return Error{std::string(to_string(g.kind)) + " goal with a value or speed that is not a finite number"};
  if (v.size() > 3) {
    const auto id = whole(v[3], 0, kMaxGoalId);
    if (!id) return Error{"goal id must be a whole number from 0 to " + std::to_string(kMaxGoalId)};
    g.id = *id;
  }
  return g;
}

os::Payload encode_status(const GoalStatus& s) {
  return os::Payload{static_cast<float>(s.event), static_cast<float>(s.id), static_cast<float>(s.kind),
                     static_cast<float>(s.achieved), static_cast<float>(s.reason)};
}

std::optional<GoalStatus> decode_status(std::span<const float> v) {
  if (v.size() < 5) return std::nullopt;
  const auto event = whole(v[0], 1, 4);
  const auto id = whole(v[1], 0, kMaxGoalId);
  const auto kind = whole(v[2], 0, 3);
  const auto reason = whole(v[4], 0, 5);
  if (!event || !id || !kind || !reason || !std::isfinite(v[3])) return std::nullopt;
  return GoalStatus{static_cast<GoalEvent>(*event), *id, static_cast<GoalKind>(*kind), v[3],
                    static_cast<GoalReason>(*reason)};
}

}  // namespace symb::robot
