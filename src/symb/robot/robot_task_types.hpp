// Robot task types: the robot layer's entries in a TaskTypeRegistry, so the shell, scenario files
// and genomes can create sensor, actuator and low-level controller tasks by name:
//
//   sensor          forwards an active Sensor's samples          device, ranges, warn_interval
//   polling_sensor  polls a PollingSensor at its period          device, ranges, warn_interval
//   actuator_sink   applies every message to an Actuator         device, ranges, warn_interval, timeout
//   actuator_task   drives a DifferentialDrive towards goals     drive, gains, tolerances, ...
//
// Tasks bind to hardware, and hardware is not a parameter: a node's devices are made by whoever
// builds the robot (the board application, a simulator backend, a test) and found here by name
// through RobotDevices, a set of lookups the caller supplies. A lookup that is missing or answers
// null makes creation fail with an error naming the device. The period is not a parameter
// either: it is TaskOptions::period, as for every task (each type has a sensible default).
#pragma once

#include <functional>
#include <memory>
#include <string_view>

#include "symb/kernel/result.hpp"
#include "symb/os/task_type_registry.hpp"
#include "symb/robot/actuator.hpp"
#include "symb/robot/differential_drive.hpp"
#include "symb/robot/polling_sensor_task.hpp"
#include "symb/robot/sensor.hpp"

namespace symb::robot {

// Finds a node's devices by name. The lookups are called when a task is created, on the
// creating thread; what they return must stay valid while the task holds it (shared ownership).
struct RobotDevices {
  std::function<std::shared_ptr<Sensor>(std::string_view)> sensor;
  std::function<std::shared_ptr<PollingSensor>(std::string_view)> polling_sensor;
  std::function<std::shared_ptr<Actuator>(std::string_view)> actuator;
  std::function<std::shared_ptr<DifferentialDrive>(std::string_view)> drive;
};

// Adds the four types above. Fails (adding nothing more) when a name is already taken.
kernel::Status register_robot_task_types(os::TaskTypeRegistry& registry, RobotDevices devices);

}  // namespace symb::robot
