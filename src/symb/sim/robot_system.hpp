// RobotSystem: one robot's control system built from its scenario entry: a Node (the robot's own
// operating system instance), the task-type registry it creates tasks from, the device tasks
// (a Thymio's `ir`, `wheels`; a 3D module's `ir`, `hinge_state`, `hinge`, `wheels`; the optional
// ones when named) and the scenario's tasks and hooks. The same builder serves the in-process 2D
// run (device tasks over simulated drivers), a 3D module of an organism (over its MuJoCo
// devices, RobotDevices::module) and the board of a hardware-in-the-loop pair (device tasks over
// the serial link), which is what makes them run the same task graph. Hooks to other robots'
// tasks (RobotSpec::remote_hooks) are not made here: they ride the organism bus.
//
// Build order, and why: registry first (the node keeps a pointer to it), then the device tasks
// (hooks may name them), then the scenario's tasks in file order, then its hooks. Any failure
// stops the build with an error located in the scenario file; the half-built node is destroyed
// before the error is returned, so nothing of it keeps running.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "symb/kernel/executor.hpp"
#include "symb/kernel/result.hpp"
#include "symb/os/node.hpp"
#include "symb/os/task_type_registry.hpp"
#include "symb/robot/actuator.hpp"
#include "symb/robot/robot_task_types.hpp"
#include "symb/robot/sensor.hpp"
#include "symb/sim/scenario.hpp"

namespace symb::sim {

class LocalRadio;

// Resolves a program reference (an MDL2e file named in a task parameter) to its text.
using ProgramReader = std::function<kernel::Result<std::string>(std::string_view)>;

// Reads files relative to `base_dir` (absolute paths as they are), at most 1 MiB each.
ProgramReader file_program_reader(std::string base_dir);

// The node seed of robot `index` in a run seeded with `seed`: the two mixed (splitmix64), so the
// robots of one run draw different numbers and a robot draws the same ones in every run, in
// process or on a board.
std::uint64_t robot_node_seed(std::uint64_t seed, std::size_t index);

// The devices behind the default device tasks.
struct RobotDevices {
  std::shared_ptr<robot::Sensor> ir;        // 7 channels
  std::shared_ptr<robot::Actuator> wheels;  // 2 channels, Thymio motor units
  std::shared_ptr<robot::Sensor> pose;      // 3 channels (simulation only; may be null)
  std::shared_ptr<robot::Sensor> ground;    // 2 channels (simulation only; may be null)
  // The world's radio medium (simulation only; may be null) and this robot's index on it: the
  // robot then gets a device task kRadioTaskName, made before the scenario's own tasks.
  LocalRadio* radio = nullptr;
  std::size_t radio_index = 0;
  // A 3D module's devices by name (MujocoRunner::device_lookups), set instead of the four above:
  // the robot task types bind to them, and the device tasks are the module's (ir, hinge_state,
  // hinge, wheels when it has them, connector_<name> when named; see scenario.hpp).
  std::optional<robot::RobotDevices> module;
};

struct RobotSystemOptions {
  kernel::Duration control_period = std::chrono::milliseconds(30);
  std::uint64_t seed = 1;  // the node's seed (its random streams)
  std::size_t log_capacity = 1024;
  ProgramReader read_program;
  // When set, makes the device tasks instead of the defaults (a `sensor` task over devices.ir and
  // an `actuator_sink` over devices.wheels whose watchdog stops the wheels 1.5 control periods
  // after the last command; `sensor` tasks over devices.pose and devices.ground when the robot's
  // hooks name them). It must create tasks named kIrTaskName and kWheelsTaskName.
  std::function<kernel::Status(os::Node&)> make_device_tasks;
  // Device tasks made even when no hook of the robot names them (a remote hook's end on this
  // robot, an event's task): the optional ones (pose, ground, connector_<name>) are made only
  // when used, each being a task woken every period.
  std::vector<std::string> named_device_tasks;
  // The types every identical robot shares (shared_scenario_task_types, made with the same
  // read_program): the robot's own registry then holds only its device task types, over these.
  // Null: the robot registers every type itself. Ignored for a 3D module (its controllers' types
  // hold the module's devices).
  std::shared_ptr<const os::TaskTypeRegistry> shared_types;
};

// The port layouts of device task `task` (kIrTaskName, kGroundTaskName, kHingeStateTaskName and
// every connector_<name> send a sensor vector, kPoseTaskName a pose, and these read no messages;
// kWheelsTaskName takes a wheel command, kHingeTaskName a hinge target [rad]; other names declare
// nothing). The
// device tasks are made with these (TaskOptions::ports), however they are made (the default
// `sensor` and `actuator_sink` tasks, whose types say only `any`, or a board's tasks made in
// code), so that Node::hook refuses `ir -> wheels` from the shell, a scenario or a genome alike.
os::PortDeclaration device_task_ports(std::string_view task);

// Registers every task type a scenario may name: the robot layer's (bound to `devices`, which
// may be empty for checking only), the control layer's (mdl2e, ...) and the evo layer's (fitness,
// one_plus_one).
kernel::Status register_scenario_task_types(os::TaskTypeRegistry& registry, RobotDevices devices,
                                            ProgramReader read_program);

// The control and evo layers' types of a 2D robot (those of register_scenario_task_types that hold
// nothing of one robot), in a registry that every robot of a session may share read-only
// (RobotSystemOptions::shared_types): one copy of their schemas and factories instead of one per
// robot.
kernel::Result<std::shared_ptr<const os::TaskTypeRegistry>> shared_scenario_task_types(ProgramReader read_program);
// The same, with the types `more` adds (plugins: sim::SessionOptions::task_types).
kernel::Result<std::shared_ptr<const os::TaskTypeRegistry>> shared_scenario_task_types(
    ProgramReader read_program, const std::function<kernel::Status(os::TaskTypeRegistry&)>& more);

class RobotSystem;
// The robot named `name` among `robots`, or null; the first cycle of answers one of their nodes
// cut (os/message.hpp, kMaxHops), or empty. What every session asks of its robots.
RobotSystem* find_robot(const std::vector<std::unique_ptr<RobotSystem>>& robots, std::string_view name);
std::string first_cycle_error(const std::vector<std::unique_ptr<RobotSystem>>& robots);

class RobotSystem {
 public:
  static kernel::Result<std::unique_ptr<RobotSystem>> build(kernel::Executor& executor, const RobotSpec& spec,
                                                            RobotDevices devices, RobotSystemOptions options);
  ~RobotSystem();
  RobotSystem(const RobotSystem&) = delete;
  RobotSystem& operator=(const RobotSystem&) = delete;

  const std::string& name() const { return name_; }
  os::Node& node() { return *node_; }
  const os::TaskTypeRegistry& types() const { return *types_; }
  // The robot's own registry, to add types to at runtime (the shell's `load`): on the robot's
  // own context, like any change to its node.
  os::TaskTypeRegistry& own_types() { return *types_; }

 private:
  RobotSystem() = default;
  std::string name_;
  std::unique_ptr<os::TaskTypeRegistry> types_;  // declared before node_: outlives it
  std::unique_ptr<os::Node> node_;
};

}  // namespace symb::sim
