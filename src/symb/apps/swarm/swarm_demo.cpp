#include "symb/apps/swarm/swarm_demo.hpp"

#include <algorithm>
#include <chrono>
#include <fstream>
#include <memory>
#include <thread>

#include "symb/apps/cli_args.hpp"
#include "symb/apps/swarm/kinematics_task.hpp"
#include "symb/apps/swarm/proximity_task.hpp"
#include "symb/apps/swarm/trail_task.hpp"
#include "symb/apps/swarm/trajectory_svg.hpp"
#include "symb/apps/swarm/wander_task.hpp"
#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/thread_executor.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/shell/tcp_shell.hpp"

namespace symb::apps {

using kernel::Error;
using WallClock = std::chrono::steady_clock;

namespace {

constexpr kernel::Duration kProgressStep = std::chrono::milliseconds(100);

double seconds_since(WallClock::time_point t0) { return std::chrono::duration<double>(WallClock::now() - t0).count(); }

// The type's own defaults (period, priority, queue), held back from starting: hooks are made
// first, so that no message of the first instant goes nowhere.
os::TaskOptions unstarted(const os::TaskTypeRegistry& types, std::string_view type) {
  os::TaskOptions o = types.find(type)->defaults;
  o.autostart = false;
  return o;
}

kernel::Status build_robot(os::Node& node, const os::TaskTypeRegistry& types, double arena,
                           swarm::TrajectoryLog& trajectory) {
  const os::ParamAssignment arena_param{"arena", os::format_param_value(arena)};
  const std::span<const os::ParamAssignment> with_arena(&arena_param, 1);
  auto kinematics = node.create("kinematics", "kinematics", with_arena, unstarted(types, "kinematics"));
  if (!kinematics) return Error{kinematics.error()};
  auto proximity = node.create("proximity", "proximity", with_arena, unstarted(types, "proximity"));
  if (!proximity) return Error{proximity.error()};
  auto wander = node.create("wander", "wander", {}, unstarted(types, "wander"));
  if (!wander) return Error{wander.error()};
  auto trail = node.create("trail", std::make_unique<swarm::TrailTask>(trajectory),
                           os::TaskOptions{.priority = 0, .period = {}, .queue_capacity = 4, .autostart = false});
  if (!trail) return Error{trail.error()};

  const std::pair<os::TaskId, os::TaskId> wires[] = {
      {*kinematics, *proximity}, {*proximity, *wander}, {*wander, *kinematics}, {*kinematics, *trail}};
  for (const auto& [from, to] : wires)
    if (auto h = node.hook(from, to); !h) return Error{h.error()};
  for (os::TaskId id : {*kinematics, *proximity, *wander, *trail})
    if (auto st = node.start(id); !st) return st;
  return {};
}

RobotFigures figures(const swarm::TrajectoryLog& t) {
  RobotFigures f;
  f.path_length = t.path_length();
  f.min_x = t.min_x();
  f.max_x = t.max_x();
  f.min_y = t.min_y();
  f.max_y = t.max_y();
  if (auto p = t.last()) {
    f.final_x = p->x;
    f.final_y = p->y;
  }
  f.poses = t.samples();
  f.contact_poses = t.contact_samples();
  return f;
}

kernel::Status check_options(const SwarmOptions& o) {
  if (o.nodes < 1 || o.nodes > kMaxSwarmNodes)
    return Error{"nodes must be from 1 to " + std::to_string(kMaxSwarmNodes) + ", not " + std::to_string(o.nodes)};
  if (o.realtime && o.nodes > kMaxRealtimeSwarmNodes)
    return Error{"a realtime swarm runs four threads per robot: at most " + std::to_string(kMaxRealtimeSwarmNodes) +
                 " nodes, not " + std::to_string(o.nodes)};
  if (o.duration <= kernel::Duration{0} || o.duration > kMaxSwarmDuration)
    return Error{"duration must be more than 0 and at most 24 h"};
  if (!(o.arena >= 0.2 && o.arena <= 1000)) return Error{"arena must be from 0.2 to 1000 m"};
  return {};
}

}  // namespace

kernel::Status register_swarm_task_types(os::TaskTypeRegistry& registry) {
  for (auto type : {swarm::KinematicsTask::type(), swarm::ProximityTask::type(), swarm::WanderTask::type()})
    if (auto st = registry.add(std::move(type)); !st) return st;
  return {};
}

std::uint64_t swarm_node_seed(std::uint64_t run_seed, std::size_t index) {
  return kernel::RandomStream(run_seed, index + 1).next_u64();
}

std::uint64_t combine_trace_hashes(std::span<const std::uint64_t> hashes) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (std::uint64_t v : hashes)
    for (int b = 0; b < 8; ++b) h = (h ^ ((v >> (8 * b)) & 0xff)) * 0x100000001b3ULL;
  return h;
}

kernel::Result<SwarmResult> run_swarm(const SwarmOptions& options) {
  if (auto st = check_options(options); !st) return Error{st.error()};

  os::TaskTypeRegistry types;
  if (auto st = register_swarm_task_types(types); !st) return Error{st.error()};

  SwarmResult result;
  result.nodes = options.nodes;
  result.seed = options.seed;
  result.realtime = options.realtime;
  result.arena = options.arena;
  // A fixed budget of points for the picture, shared by all robots.
  const std::size_t points_per_robot = std::clamp<std::size_t>(400000 / options.nodes, 16, 2000);
  result.trajectories.assign(options.nodes, swarm::TrajectoryLog(points_per_robot, 10));

  // Declared before the nodes, so destroyed after them: a node must not outlive its executor.
  std::unique_ptr<kernel::VirtualTimeExecutor> virtual_exec;
  std::unique_ptr<kernel::ThreadExecutor> thread_exec;
  kernel::Executor* exec = nullptr;
  if (options.realtime) {
    thread_exec = std::make_unique<kernel::ThreadExecutor>();
    exec = thread_exec.get();
  } else {
    virtual_exec = std::make_unique<kernel::VirtualTimeExecutor>();
    exec = virtual_exec.get();
  }

  std::vector<std::unique_ptr<os::Node>> nodes;
  nodes.reserve(options.nodes);
  for (std::size_t i = 0; i < options.nodes; ++i) {
    os::NodeConfig config;
    config.name = "robot-" + std::to_string(i);
    config.seed = swarm_node_seed(options.seed, i);
    config.types = &types;
    auto& node = *nodes.emplace_back(std::make_unique<os::Node>(*exec, std::move(config)));
    node.set_tracing(true);
    node.log().info("swarm", "robot " + std::to_string(i) + " of " + std::to_string(options.nodes) + ", run seed " +
                                 std::to_string(options.seed) + ", node seed " + std::to_string(node.seed()));
    if (auto st = build_robot(node, types, options.arena, result.trajectories[i]); !st)
      return Error{node.name() + ": " + st.error()};
  }

  std::unique_ptr<shell::TcpShellServer> shell_server;
  if (options.shell_port) {
    shell::TcpShellOptions so;
    so.port = *options.shell_port;
    auto server = shell::TcpShellServer::start(*nodes.front(), so);
    if (!server) return Error{"shell: " + server.error()};
    shell_server = std::move(server).value();
    if (options.on_shell)
      options.on_shell(shell_server->host() + ":" + std::to_string(shell_server->port()), shell_server->token());
  }

  const double total = kernel::to_seconds(options.duration);
  const auto report = [&](double done, WallClock::time_point t0) {
    if (options.on_progress) options.on_progress(SwarmProgress{done, total, seconds_since(t0)});
  };
  const WallClock::time_point wall0 = WallClock::now();
  if (virtual_exec) {
    // In slices, only to report progress: events are ordered by time, so slicing changes nothing.
    const kernel::Time end = virtual_exec->now() + options.duration;
    while (virtual_exec->now() < end) {
      result.events += virtual_exec->run_until(std::min(virtual_exec->now() + kProgressStep, end));
      report(kernel::to_seconds(virtual_exec->now()), wall0);
    }
  } else {
    const kernel::Clock& clock = thread_exec->clock();
    const kernel::Time start = clock.now(), end = start + options.duration;
    for (kernel::Time t = start; t < end; t = clock.now()) {
      std::this_thread::sleep_for(std::min(kProgressStep, end - t));
      report(std::min(kernel::to_seconds(clock.now() - start), total), wall0);
    }
  }
  result.wall_seconds = seconds_since(wall0);
  result.simulated_seconds = total;
  result.real_time_factor = result.wall_seconds > 0 ? total / result.wall_seconds : 0;

  std::vector<std::uint64_t> hashes;
  hashes.reserve(nodes.size());
  for (const auto& node : nodes) {
    hashes.push_back(node->trace_hash());
    result.traffic += node->traffic();
  }
  result.trace_hash = combine_trace_hashes(hashes);
  nodes.front()->log().info("swarm", "run ended after " + fixed(total, 3) + " s");
  result.node0_log = nodes.front()->log().since(0);

  shell_server.reset();  // its sessions are tasks of robot 0: close them while the node exists
  // Destroying the nodes stops every task (and, under threads, waits for their handlers), after
  // which the trajectories are ours alone to read.
  nodes.clear();
  result.robots.reserve(options.nodes);
  for (const auto& t : result.trajectories) result.robots.push_back(figures(t));

  if (options.out_dir) {
    auto files = write_swarm_outputs(result, *options.out_dir);
    if (!files) return Error{files.error()};
    result.out_dir = *options.out_dir;
    result.files = std::move(files).value();
  }
  return result;
}

kernel::Result<std::vector<std::filesystem::path>> write_swarm_outputs(const SwarmResult& r,
                                                                       const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return Error{"cannot create output folder '" + dir.string() + "': " + ec.message()};
  if (!fs::is_directory(dir, ec)) return Error{"output path '" + dir.string() + "' is not a folder"};

  std::vector<fs::path> written;
  const auto write = [&](const char* name, const auto& fill) -> kernel::Status {
    const fs::path path = dir / name;
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    if (!out) return Error{"cannot write '" + path.string() + "'"};
    fill(out);
    out.close();
    if (!out) return Error{"error while writing '" + path.string() + "'"};
    written.push_back(path);
    return {};
  };

  double mean_path = 0, min_path = 0, max_path = 0;
  std::uint64_t poses = 0, contacts = 0;
  for (std::size_t i = 0; i < r.robots.size(); ++i) {
    const RobotFigures& f = r.robots[i];
    mean_path += f.path_length;
    min_path = i == 0 ? f.path_length : std::min(min_path, f.path_length);
    max_path = std::max(max_path, f.path_length);
    poses += f.poses;
    contacts += f.contact_poses;
  }
  if (!r.robots.empty()) mean_path /= static_cast<double>(r.robots.size());

  const std::string caption = std::to_string(r.nodes) + " robots, seed " + std::to_string(r.seed) + ", " +
                              fixed(r.simulated_seconds, 1) + " s" + (r.realtime ? " (real time)" : " simulated") +
                              ", arena " + fixed(r.arena, 2) + " m, trace hash " + hex64(r.trace_hash);
  if (auto st = write("trajectories.svg",
                      [&](std::ostream& out) { swarm::write_trajectory_svg(out, r.arena, r.trajectories, caption); });
      !st)
    return Error{st.error()};

  if (auto st = write(
          "summary.txt",
          [&](std::ostream& out) {
            const os::TrafficCounters& t = r.traffic;
            out << "demo: swarm\n"
                << "nodes: " << r.nodes << "\n"
                << "seed: " << r.seed << "\n"
                << "executor: "
                << (r.realtime ? "thread (wall clock, not deterministic)" : "virtual-time (deterministic)") << "\n"
                << "arena: " << fixed(r.arena, 3) << " m\n"
                << "simulated seconds: " << fixed(r.simulated_seconds, 3) << "\n"
                << "wall seconds: " << fixed(r.wall_seconds, 3) << "\n"
                << "real-time factor: " << fixed(r.real_time_factor, 2) << "\n";
            if (!r.realtime) out << "executor events: " << r.events << "\n";
            out << "messages attempted: " << t.attempted << "\n"
                << "messages delivered: " << t.delivered << "\n"
                << "messages dropped: " << t.dropped() << " (overwritten " << t.overwritten << ", refused " << t.refused
                << ", suppressed " << t.suppressed << ", inhibited " << t.inhibited << ", discarded " << t.discarded
                << ")\n"
                << "path length per robot: mean " << fixed(mean_path, 3) << " m, min " << fixed(min_path, 3)
                << " m, max " << fixed(max_path, 3) << " m\n"
                << "poses touching a wall: "
                << fixed(poses > 0 ? 100.0 * static_cast<double>(contacts) / static_cast<double>(poses) : 0, 3)
                << " %\n"
                << "trace hash: " << hex64(r.trace_hash) << "\n";
          });
      !st)
    return Error{st.error()};

  if (auto st = write("syslog.txt",
                      [&](std::ostream& out) {
                        out << "# SysLog of node robot-0 (" << r.node0_log.size() << " entries)\n";
                        for (const os::LogEntry& e : r.node0_log) out << os::format_log_entry(e) << "\n";
                      });
      !st)
    return Error{st.error()};
  return written;
}

}  // namespace symb::apps
