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
// A 3D world (`world: {kind: mujoco}`, run by mujoco/organism_session.hpp) holds modules instead:
// each robot names its module kind file (`module:`), and its device tasks come from the module's
// devices (mujoco/mujoco_devices.hpp):
//   ir            4 IR proximities (front, back, left, right), 0..1, per control period (port 0)
//   hinge_state   [angle rad, speed rad/s] of the hinge per control period (port 0)
//   hinge         the hinge's position servo: takes [target rad]
//   wheels        as in 2D, [left, right] Thymio motor units (kinds with wheels only)
//   connector_<n> [state, open, peer, beacon distance, bearing, heading] of connector n, made only when the robot's
//   hooks name it;
//                 its ioctls (open, close, latch, unlatch, state) reach it from a shell or an event
// Modules may start docked (`world.docked`), a hook may reach a task on another module over the
// organism bus (`to: robot/task`, RobotSpec::remote_hooks), and in either world `events` run shell
// lines on a robot's node at given times. Every name above, `connector_` with any suffix
// included, is taken in both worlds (is_device_task_name), so a file means one thing in each.
//
// File format: docs/scenarios.md. Parsing: scenario_parser.cpp (yaml-cpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"
#include "symb/os/hook.hpp"
#include "symb/os/param.hpp"
#include "symb/os/task_type_registry.hpp"
#include "symb/sim/mujoco/mjcf_model.hpp"
#include "symb/sim/mujoco/module_kind.hpp"
#include "symb/sim/world_spec.hpp"

namespace symb::sim {

// Names of the device tasks every robot has.
inline constexpr std::string_view kIrTaskName = "ir";
inline constexpr std::string_view kWheelsTaskName = "wheels";
inline constexpr std::string_view kPoseTaskName = "pose";
inline constexpr std::string_view kGroundTaskName = "ground";
inline constexpr std::string_view kRadioTaskName = "radio";
// ... and those only a 3D module has.
inline constexpr std::string_view kHingeTaskName = "hinge";
inline constexpr std::string_view kHingeStateTaskName = "hinge_state";
inline constexpr std::string_view kConnectorTaskPrefix = "connector_";

// Whether `name` is one of the device tasks above (taken, radio included, even where the world
// has no radio: a scenario must not mean something else once it gets one; and the 3D ones in a
// 2D world too, for the same reason).
inline bool is_device_task_name(std::string_view name) {
  return name == kIrTaskName || name == kWheelsTaskName || name == kPoseTaskName || name == kGroundTaskName ||
         name == kRadioTaskName || name == kHingeTaskName || name == kHingeStateTaskName ||
         name.substr(0, kConnectorTaskPrefix.size()) == kConnectorTaskPrefix;
}

// Every robot keeps a disc of this radius (cm) around its start point free: no wall surface and
// no other robot's disc may reach into it. Thymio2 is about 11 cm across, so 8 cm leaves it
// room to turn on the spot before it first senses anything.
inline constexpr double kStartClearance = 8.0;

// Bounds that keep a hostile file from costing more than a moment to read.
inline constexpr std::size_t kMaxScenarioBytes = 1 << 20;
inline constexpr int kMaxNesting = 64;            // mappings and sequences inside each other
inline constexpr std::size_t kMaxRobots = 20000;  // after `count` expansion
inline constexpr std::size_t kMaxWalls = 2000;
inline constexpr std::size_t kMaxZones = 100;
inline constexpr std::size_t kMaxEvents = 10000;
inline constexpr std::size_t kMaxPlugins = 64;   // `plugins:` entries
inline constexpr std::size_t kMaxDocked = 4000;  // pairs in world.docked
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

// A hook from a task of this robot to a task of another robot (`to: robot/task`), carried by the
// organism bus (3D worlds with world.bus). The parser checks that both ends exist; whoever runs
// the scenario wires it (OrganismSession::wire_remote_hooks).
struct RemoteHookSpec {
  std::string from;          // a task of this robot (its own or a device task)
  std::string to_robot;      // the other robot's name
  std::size_t to_index = 0;  // ... and its index in Scenario::robots
  std::string to;            // a task of that robot
  os::HookOptions options;
  SourceLocation where;     // the hook's entry
  SourceLocation to_where;  // its `to` value
};

struct RobotSpec {
  std::string name;
  RobotKind kind = RobotKind::kThymio2;
  // Where it starts: theta in radians (the file gives degrees); x, y in cm. In a 3D world, also
  // for a module placed by docking (the place docking computed).
  Pose start;
  std::vector<TaskSpec> tasks;
  std::vector<HookSpec> hooks;
  std::vector<RemoteHookSpec> remote_hooks;  // 3D worlds with a bus only
  SourceLocation where;
  // 3D worlds only: the module kind file as written (relative to the scenario's folder), its
  // contents, and the start in the world's units (metres, radians).
  std::string module;
  SourceLocation module_where;
  sim::mujoco::ModuleKind module_kind;
  sim::mujoco::StartPose module_start;
};

// Which world a scenario describes: the 2D Enki arena (the default) or the 3D MuJoCo world of
// modules (`world: {kind: mujoco}`).
enum class WorldKind : std::uint8_t { kEnki, kMujoco };

// world.bus: the organism bus's wire (CAN-like): bits per second and the delay of one frame.
struct BusSpec {
  std::uint64_t bandwidth = 1'000'000;                      // bit/s
  kernel::Duration latency = std::chrono::milliseconds(1);  // per frame, on top of its bits
  SourceLocation where;
};

// One world.docked pair: connector `connector_a` of robot `a` latched to `connector_b` of robot
// `b` before the run starts (indices into Scenario::robots, names as in the module kinds).
struct DockSpec {
  std::size_t a = 0;
  std::string connector_a;
  std::size_t b = 0;
  std::string connector_b;
  SourceLocation where;
};

// What only a 3D world has.
// world.battery: every module gets a battery (sim/mujoco/module_battery.hpp) drained by its
// actuators; without it, modules have power without end.
struct BatterySpec {
  double capacity = 3600;  // J
  bool share = false;      // docked modules share their charge from the start
  SourceLocation where;
};

struct OrganismWorldSpec {
  std::vector<DockSpec> docked;
  std::optional<BusSpec> bus;
  std::optional<BatterySpec> battery;
};

// One `events` entry: at `at` after the run's start, `line` runs through a shell on robot
// `robot`'s node (the same commands a user has); the reply goes to that node's log.
struct EventSpec {
  kernel::Duration at{0};
  std::size_t robot = 0;  // index into Scenario::robots
  std::string line;
  SourceLocation where;
};

// A plugin named in a scenario: its path (relative ones resolved against the scenario's folder)
// and where the file names it.
struct PluginRef {
  std::string path;
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
  WorldKind world_kind = WorldKind::kEnki;
  WorldSpec world;                // the 2D world (its arena is empty in a 3D one)
  OrganismWorldSpec organism;     // the 3D world's docks and bus
  std::vector<RobotSpec> robots;  // `count: N` entries are expanded, names made unique
  std::vector<EventSpec> events;  // in file order (those at one time run in that order)
  // `plugins:` task-type plugins (os/plugin.hpp) the session loads before it checks the tasks,
  // paths resolved against base_dir, each with where it was written.
  std::vector<PluginRef> plugins;
};

// Reads a module kind file named in a scenario (the name as written, resolved by the reader) and
// gives its text; parse_scenario parses it, so its errors keep their own file:line:column.
using ModuleKindReader = std::function<kernel::Result<std::string>(std::string_view)>;
struct ScenarioParseOptions {
  // Default: files relative to the folder of the scenario file's name.
  ModuleKindReader read_module_kind;
};

// Structure, values and geometry: unknown or missing keys, wrong types, bad durations, walls
// outside the arena, robots starting inside a wall or another robot, duplicate names, hooks to
// tasks that the robot does not have. Never throws.
// In a 3D world also the modules: kind files that read and parse, starts clear of each other,
// docked pairs whose connectors meet within MujocoWorld's latch tolerances; events at times within
// the run, for robots that exist, with lines the shell can split; remote hooks between tasks that
// exist.
kernel::Result<Scenario> parse_scenario(std::string_view yaml_text, std::string_view file_name,
                                        const ScenarioParseOptions& options = {});
// Reads `path` and parses it; base_dir is the file's directory.
kernel::Result<Scenario> load_scenario(const std::string& path);

// Against the task types a runner offers: every task type exists and every parameter resolves
// against its schema (names, types, ranges). Errors point at the task or the parameter.
kernel::Status check_scenario(const Scenario& scenario, const os::TaskTypeRegistry& types);

}  // namespace symb::sim
