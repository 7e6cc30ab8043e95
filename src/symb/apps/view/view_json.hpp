// The web view's frames: JSON texts the run sends to the page (web/view/view.js reads them). Pure
// functions from plain data to text; the live view (live_view.hpp) decides when to make which.
//   hello   once per client: the world (arena, walls), the robots' names, the controls' state
//   step    every robot's pose: "xy": [x, y, heading, ...] as a flat number list (cm, 0.1 cm;
//           degrees), every `stride`-th robot when there are more than a frame should carry
//   graph   one robot's task graph, from the same node calls as the shell's `tasks` and `hooks`:
//           tasks with state, priority, period, queue fill and traffic; hooks with priority,
//           policy, suppression window, state and their accounting
//   log     new SysLog lines of that robot (os::format_log_entry, as syslog.txt)
//   probes  that robot's latest probe sample per (task, channel): hormone levels, activations
//   status  paused, speed, simulated time, frames dropped for slow clients
//   shell   a shell session's output
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "symb/os/hook.hpp"
#include "symb/os/syslog.hpp"
#include "symb/os/task.hpp"
#include "symb/sim/world.hpp"
#include "symb/sim/world_spec.hpp"

namespace symb::apps::view {

struct HelloInfo {
  std::string scenario;
  const sim::WorldSpec* world = nullptr;  // null: no 2D world (a 3D run)
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

struct ProbeValue {
  double seconds = 0;
  std::string task, channel;
  std::vector<float> values;
};
std::string probes_json(std::string_view robot, std::span<const ProbeValue> probes);

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
