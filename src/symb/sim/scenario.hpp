// Scenario: one experiment as plain data, read from a YAML file: the world (arena, maze walls),
// the robots (where they start) and, for each robot, the tasks of its control system, their
// parameters and the hooks between them. A scenario is checked completely before anything runs;
// every error names the file, line and column of the offending value.
//
// Every robot gets two device tasks from whoever runs it, so a scenario's hooks can name them:
//   ir      the 7 IR proximity sensors: one message of 7 values per control period (port 0)
//   wheels  the wheel actuator: takes [left, right] in Thymio motor units, -500..500
// and, in simulation, two more that are made only when the robot's hooks name them:
//   pose    [x cm, y cm, heading rad] per control period (an overhead tracker)
//   ground  [left, right] floor reflectance 0..1 per control period (see WorldSpec::zones)
// and every robot of a world that declares a radio (world.radio) has one more:
//   radio   a short-range radio (sim::LocalRadio): bytes sent to it go on air, bytes heard come
//           out with the sender's robot index (mEDEA's medium)
// In-process they sit on simulated drivers; on a board, on the serial link (see docs/scenarios.md).
//
// File format: docs/scenarios.md. Parsing: scenario_parser.cpp (yaml-cpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"
#include "symb/os/hook.hpp"
#include "symb/os/param.hpp"
#include "symb/os/task_type_registry.hpp"
#include "symb/sim/world_spec.hpp"

namespace symb::sim {

// Names of the device tasks every robot has.
inline constexpr std::string_view kIrTaskName = "ir";
inline constexpr std::string_view kWheelsTaskName = "wheels";
inline constexpr std::string_view kPoseTaskName = "pose";
inline constexpr std::string_view kGroundTaskName = "ground";
inline constexpr std::string_view kRadioTaskName = "radio";

// Whether `name` is one of the device tasks above (taken, radio included, even where the world
// has no radio: a scenario must not mean something else once it gets one).
inline bool is_device_task_name(std::string_view name) {
  return name == kIrTaskName || name == kWheelsTaskName || name == kPoseTaskName || name == kGroundTaskName ||
         name == kRadioTaskName;
}

// Every robot keeps a disc of this radius (cm) around its start point free: no wall surface and
// no other robot's disc may reach into it. Thymio2 is about 11 cm across, so 8 cm leaves it
// room to turn on the spot before it first senses anything.
inline constexpr double kStartClearance = 8.0;

// Bounds that keep a hostile file from costing more than a moment to read.
inline constexpr std::size_t kMaxScenarioBytes = 1 << 20;
inline constexpr int kMaxNesting = 64;           // mappings and sequences inside each other
inline constexpr std::size_t kMaxRobots = 1000;  // after `count` expansion
inline constexpr std::size_t kMaxWalls = 2000;
inline constexpr std::size_t kMaxZones = 100;
// The longest run: a scenario's `duration` and the commands' --duration (symb run, sim, evolve)
// all stop here. 168 h (a week) simulated is hours of wall clock for a swarm at full speed; and
// a HIL run's sequence numbers last 139 h at 30 ms.
inline constexpr kernel::Duration kMaxRunDuration = std::chrono::hours(168);

struct TaskSpec {
  std::string name;
  std::string type;
  // Values as text, exactly as a shell line would give them; `column` is unused (see where).
  std::vector<os::ParamAssignment> params;
  std::vector<SourceLocation> param_where;  // one per params entry: where its name is
  std::optional<int> priority;
  std::optional<kernel::Duration> period;
  std::optional<std::size_t> queue_capacity;
  bool autostart = true;
  SourceLocation where;       // the task's entry
  SourceLocation type_where;  // its `type` value
};

struct HookSpec {
  std::string from;
  std::string to;
  os::HookOptions options;
  SourceLocation where;
};

struct RobotSpec {
  std::string name;
  RobotKind kind = RobotKind::kThymio2;
  Pose start;  // theta in radians; the file gives degrees
  std::vector<TaskSpec> tasks;
  std::vector<HookSpec> hooks;
  SourceLocation where;
};

struct Scenario {
  std::string name;
  std::string description;
  std::string file;      // as given to load_scenario / parse_scenario
  std::string base_dir;  // directory relative file names in parameters are resolved against
  std::uint64_t seed = 1;
  kernel::Duration duration = std::chrono::minutes(10);
  kernel::Duration control_period = std::chrono::milliseconds(30);
  WorldSpec world;
  std::vector<RobotSpec> robots;  // `count: N` entries are expanded, names made unique
};

// Structure, values and geometry: unknown or missing keys, wrong types, bad durations, walls
// outside the arena, robots starting inside a wall or another robot, duplicate names, hooks to
// tasks that the robot does not have. Never throws.
kernel::Result<Scenario> parse_scenario(std::string_view yaml_text, std::string_view file_name);
// Reads `path` and parses it; base_dir is the file's directory.
kernel::Result<Scenario> load_scenario(const std::string& path);

// Against the task types a runner offers: every task type exists and every parameter resolves
// against its schema (names, types, ranges). Errors point at the task or the parameter.
kernel::Status check_scenario(const Scenario& scenario, const os::TaskTypeRegistry& types);

}  // namespace symb::sim
