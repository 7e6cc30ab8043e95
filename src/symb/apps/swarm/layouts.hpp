// Message layouts of the swarm demo: which number sits where in what each of its task types
// sends. The tasks agree on these layouts rather than on each other's classes, so any one of them
// can be replaced at runtime by another task that speaks the same layout (a real sensor driver, an
// evolved controller) without touching the others.
#pragma once

#include <cstddef>

#include "symb/os/ids.hpp"

namespace symb::apps::swarm {

// Sent by "kinematics" every tick: the robot's pose in the arena frame (metres, radians, origin at
// the arena's south-west corner, heading counter-clockwise from east).
struct PoseLayout {
  static constexpr os::Port kPort = 0;
  static constexpr std::size_t kX = 0;
  static constexpr std::size_t kY = 1;
  static constexpr std::size_t kHeading = 2;
  static constexpr std::size_t kSpeed = 3;     // forward speed, m/s
  static constexpr std::size_t kTurnRate = 4;  // rad/s, positive to the left
  static constexpr std::size_t kContact = 5;   // 1 while the body touches a wall, else 0
  static constexpr std::size_t kCount = 6;
};

// Sent by "proximity" every period: the free distance along four rays fixed to the robot body,
// each at most kRange (which travels along so that a controller need not know the sensor).
struct ProximityLayout {
  static constexpr os::Port kPort = 0;
  static constexpr std::size_t kFront = 0;
  static constexpr std::size_t kLeft = 1;
  static constexpr std::size_t kBack = 2;
  static constexpr std::size_t kRight = 3;
  static constexpr std::size_t kRange = 4;
  static constexpr std::size_t kCount = 5;
};

// Sent by "wander": wheel surface speeds, m/s, positive forward.
struct WheelLayout {
  static constexpr os::Port kPort = 0;
  static constexpr std::size_t kLeft = 0;
  static constexpr std::size_t kRight = 1;
  static constexpr std::size_t kCount = 2;
};

}  // namespace symb::apps::swarm
