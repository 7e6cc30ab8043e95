// Robot ports: the topics the robot layer's tasks agree on. A port is a sender's output channel;
// a receiver that listens to several senders (an actuator task gets odometry from a sensor task
// and goals from a controller) tells their messages apart by port, so senders and receivers
// must share one numbering. These are the defaults; the task types that read several ports also
// take them as parameters.
#pragma once

#include "symb/os/ids.hpp"
#include "symb/os/port_layout.hpp"

namespace symb::robot {

// Sensor values (one number per channel) and odometry.
inline constexpr os::Port kDataPort = 0;
// Goals for actuator tasks (see drive_goal.hpp).
inline constexpr os::Port kCommandPort = 1;
// Goal reports from actuator tasks: accepted, completed, aborted, rejected.
inline constexpr os::Port kStatusPort = 2;

// The message layouts task types declare on their ports (TaskType::inputs, outputs): a hook
// whose ends disagree on a port is refused at hook time. os::kAnyLayout stands for a device's own
// channels (a sensor task forwards whatever its device measures).
namespace layout {
// One number per sensor channel, as a sensor task sends it (7 for the Thymio's horizontal IR).
inline constexpr os::PortLayout kSensorVector{"sensor-vector", "one number per sensor channel"};
// [left, right] wheel speeds (Thymio units).
inline constexpr os::PortLayout kWheelCommand{"wheel-command", "[left, right] wheel speeds"};
// [x, y, heading] (cm or m, radians).
inline constexpr os::PortLayout kPose{"pose", "[x, y, heading]"};
// A motor schema's [vx, vy] vector.
inline constexpr os::PortLayout kSchemaVector{"schema-vector", "[vx, vy]"};
// [bit, 0 or 1]: sets or clears an external interrupt bit of an MDL2e program.
inline constexpr os::PortLayout kExternalBit{"external-bit", "[bit, 0 or 1]"};
// [angle]: a joint's target, rad (a hinge's position servo; an oscillator's output).
inline constexpr os::PortLayout kJointTarget{"joint-target", "[angle rad]"};
// [id, phase]: an oscillator's place in its chain and its phase, rad (control/cpg).
inline constexpr os::PortLayout kOscillatorPhase{"oscillator-phase", "[id, phase rad]"};
}  // namespace layout

// A controller's input of the IR sensor task's vectors (the maze demo's `ir -> controller`).
inline constexpr os::PortSpec kIrInput{kDataPort, "ir", layout::kSensorVector};

}  // namespace symb::robot
