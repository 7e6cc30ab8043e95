// The "swarm" demo: N robots wander in a square walled arena, each robot its own os::Node with its
// own seed and SysLog, all on one executor: the deterministic virtual-time executor by default
// (same seed, bit-identical run, far faster than real time) or the thread executor on the wall
// clock. Each node runs the same small task graph, made by name from a per-run task-type registry
// and wired by hooks:
//
//     kinematics --pose--> proximity --distances--> wander --wheel speeds--> kinematics
//          \--pose--> trail (the harness's recorder)
//
// Every node traces its message deliveries; the per-node trace hashes, combined in node order,
// give one run hash that a test compares across runs and processes.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "symb/apps/swarm/trajectory_log.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"
#include "symb/os/syslog.hpp"
#include "symb/os/task.hpp"
#include "symb/os/task_type_registry.hpp"

namespace symb::apps {

inline constexpr std::size_t kMaxSwarmNodes = 10000;
// Under the thread executor every task is an OS thread (four per robot).
inline constexpr std::size_t kMaxRealtimeSwarmNodes = 250;
// Longest run accepted, simulated or real.
inline constexpr kernel::Duration kMaxSwarmDuration = std::chrono::hours(24);

struct SwarmProgress {
  double simulated_seconds = 0;  // done so far (wall seconds under realtime)
  double total_seconds = 0;
  double wall_seconds = 0;
  double fraction() const { return total_seconds > 0 ? simulated_seconds / total_seconds : 1.0; }
};

struct SwarmOptions {
  std::size_t nodes = 100;
  std::uint64_t seed = 1;
  kernel::Duration duration = std::chrono::seconds(60);
  bool realtime = false;  // thread executor on the wall clock: not deterministic
  double arena = 4.0;     // side of the square arena, m
  // When set, run_swarm writes trajectories.svg, summary.txt and syslog.txt there.
  std::optional<std::filesystem::path> out_dir;
  // Called now and then from the running thread (every 100 ms of simulated or wall time).
  std::function<void(const SwarmProgress&)> on_progress;
  // When set (realtime runs), robot 0's command shell listens on 127.0.0.1 at this port (0: any
  // free one) while the swarm runs; on_shell is told "host:port" and the session token.
  std::optional<std::uint16_t> shell_port;
  std::function<void(const std::string& where, const std::string& token)> on_shell;
};

// One robot's figures, from every pose its kinematics sent.
struct RobotFigures {
  double path_length = 0;  // m
  double min_x = 0, max_x = 0, min_y = 0, max_y = 0;
  double final_x = 0, final_y = 0;
  std::uint64_t poses = 0;
  std::uint64_t contact_poses = 0;  // poses sent while touching a wall
};

struct SwarmResult {
  std::size_t nodes = 0;
  std::uint64_t seed = 0;
  bool realtime = false;
  double arena = 0;
  double simulated_seconds = 0;
  double wall_seconds = 0;
  double real_time_factor = 0;
  std::uint64_t events = 0;      // executor events handled (virtual time only)
  os::TrafficCounters traffic;   // summed over all nodes
  std::uint64_t trace_hash = 0;  // combine_trace_hashes() of the nodes, in node order
  std::vector<RobotFigures> robots;
  std::vector<swarm::TrajectoryLog> trajectories;
  std::vector<os::LogEntry> node0_log;       // node 0's SysLog at the end of the run
  std::filesystem::path out_dir;             // empty when nothing was written
  std::vector<std::filesystem::path> files;  // what was written
};

// Registers "kinematics", "proximity" and "wander".
kernel::Status register_swarm_task_types(os::TaskTypeRegistry& registry);

// Node `index`'s seed: independent streams for different robots, the same for the same run seed.
std::uint64_t swarm_node_seed(std::uint64_t run_seed, std::size_t index);

// FNV-1a over the hashes' 8 little-endian bytes each, in order.
std::uint64_t combine_trace_hashes(std::span<const std::uint64_t> hashes);

// Builds the swarm, runs it for options.duration and collects the figures; writes the output
// files when options.out_dir is set. Fails (with a message) on options out of range, or when the
// output folder cannot be written.
kernel::Result<SwarmResult> run_swarm(const SwarmOptions& options);

// Writes trajectories.svg, summary.txt and syslog.txt into `dir` (created if needed); returns the
// paths written.
kernel::Result<std::vector<std::filesystem::path>> write_swarm_outputs(const SwarmResult& result,
                                                                       const std::filesystem::path& dir);

}  // namespace symb::apps
