// The web view's frames: JSON texts the run sends to the page (web/view/view.js reads them). Pure
// functions from plain data to text; the live view (live_view.hpp) decides when to make which.
//   hello   once per client: the world (a 2D arena and its walls, a 3D organism's module shapes,
//           or null: a board has no world), the robots' names, the controls' state
//   step    every robot's pose: "xy": [x, y, heading, ...] as a flat number list (cm, 0.1 cm;
//           degrees), every `stride`-th robot when there are more than a frame should carry
//   graph   one robot's task graph, from the same node calls as the shell's `tasks` and `hooks`:
//           tasks with state, priority, period, queue fill and traffic; hooks with priority,
//           policy, suppression window, state and their accounting
//   log     new SysLog lines of that robot (os::format_log_entry, as syslog.txt)
//   organism every module's pose (position m, quaternion w x y z, hinge angle rad) as a flat
//           number list, and the docked connector pairs (the organism's topology)
//   probes  that robot's probe series (probe_history.hpp): the latest sample whole (hormone levels,
//           activations, ...) and the points kept since the last frame, or all of them ("full")
//   spikes  that robot's spiking networks' new spikes (time s, neuron), for the raster
//   fitness an evolution run's fitness series (probe_history.hpp), new points or all of them
//   status  paused, speed, simulated time, frames dropped for slow clients
//   shell   a shell session's output
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "symb/apps/view/probe_history.hpp"
#include "symb/os/hook.hpp"
#include "symb/os/syslog.hpp"
#include "symb/os/task.hpp"
#include "symb/sim/world.hpp"
#include "symb/sim/world_spec.hpp"

namespace symb::apps::view {

// A 3D module's shape, as the page draws it: a box of `size` (m) split across its length into a
// front half (x >= 0) and a tail that the hinge turns about `hinge_axis` (module frame).
struct ModuleShape {
  std::string name;
  std::array<double, 3> size{};
  std::array<double, 3> hinge_axis{};
  bool wheels = false;
  std::vector<std::pair<std::string, std::array<double, 3>>> connectors;  // name, position (module frame)
};

struct HelloInfo {
  std::string scenario;
  const sim::WorldSpec* world = nullptr;               // a 2D world, or
  const std::vector<ModuleShape>* organism = nullptr;  // a 3D one; neither: no world (a board)
  std::vector<std::string> robots;
  std::size_t selected = 0;
  bool virtual_time = true;  // false: --realtime, no pause/step/speed
  bool paused = false;
  double speed = 0;  // 0: as fast as possible
  double duration_seconds = 0;
};
std::string hello_json(const HelloInfo& h);

// At most `max_robots` poses (every stride-th robot, stride = ceil(n / max_robots)).
std::string step_json(std::uint64_t step, double seconds, std::span<const sim::RobotState> robots,
                      std::size_t max_robots);

std::string graph_json(std::string_view robot, std::span<const os::TaskInfo> tasks, std::span<const os::HookInfo> hooks,
                       kernel::Time now);

std::string log_json(std::string_view robot, std::span<const os::LogEntry> entries);

// A module's pose: position (m), orientation (quaternion w, x, y, z), hinge angle (rad).
struct ModulePose {
  std::array<double, 3> position{};
  std::array<double, 4> quaternion{1, 0, 0, 0};
  double hinge = 0;
};
// Two docked connectors: {module, connector, other module, other connector}, indices.
using DockedPair = std::array<std::size_t, 4>;
std::string organism_json(std::uint64_t step, double seconds, std::span<const ModulePose> modules,
                          std::span<const DockedPair> docked);

// `full`: the series' every point (the page replaces what it has); else the new ones.
std::string probes_json(std::string_view robot, std::span<const ProbeSeriesView> probes, bool full);

// New spikes of one spiking-network task: (time s, neuron) pairs, and how many did not fit.
std::string spikes_json(std::string_view robot, std::string_view task, std::span<const float> dots,
                        std::uint64_t dropped);

// An evolution's fitness series (width 1: each point's first value).
std::string fitness_json(std::string_view robot, std::string_view task, std::span<const ProbeSeriesView> series,
                         bool full);

struct StatusInfo {
  bool virtual_time = true;
  bool paused = false;
  double speed = 0;
  double seconds = 0;
  std::uint64_t frames_dropped = 0;
  bool finished = false;
};
std::string status_json(const StatusInfo& s);

std::string shell_json(std::string_view text);

}  // namespace symb::apps::view
