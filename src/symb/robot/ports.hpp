// Robot ports: the topics the robot layer's tasks agree on. A port is a sender's output channel;
// a receiver that listens to several senders (an actuator task gets odometry from a sensor task
// and goals from a controller) tells their messages apart by port, so senders and receivers
// must share one numbering. These are the defaults; the task types that read several ports also
// take them as parameters.
#pragma once

#include "symb/os/ids.hpp"

namespace symb::robot {

// Sensor values (one number per channel) and odometry.
inline constexpr os::Port kDataPort = 0;
// Goals for actuator tasks (see drive_goal.hpp).
inline constexpr os::Port kCommandPort = 1;
// Goal reports from actuator tasks: accepted, completed, aborted, rejected.
inline constexpr os::Port kStatusPort = 2;
// Internal: a device's "new data" notification, posted by a task to itself from outside any task.
inline constexpr os::Port kWakePort = 0xfffe;

}  // namespace symb::robot
