#include "symb/apps/run/run_command.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "symb/apps/interrupt_flag.hpp"
#include "symb/apps/progress_line.hpp"
#include "symb/apps/run/scenario_run.hpp"
#include "symb/evo/genome/genome.hpp"
#include "symb/os/param.hpp"
#include "symb/sim/scenario.hpp"

namespace symb::apps::run {

namespace {

using namespace std::chrono_literals;

constexpr std::string_view kCommand = "symb run";
constexpr kernel::Duration kMaxDuration = sim::kMaxRunDuration;  // a scenario's limit too

constexpr OptionSpec kOptions[] = {
    {"--out", "DIR", "output folder (default out/<scenario name>)"},
    {"--seed", "S", "seed, unsigned 64-bit (default: the scenario's)"},
    {"--duration", "D", "simulated time: 60s, 10min, ... (default: the scenario's)"},
    {"--realtime", "", "run on OS threads against the wall clock (not deterministic)"},
    {"--threads", "N",
     "2D: threads running the robots' nodes, 1-64 (default: 1, one per core from 500 robots); the same run for any N"},
    {"--speed", "X", "virtual time at X times the wall clock (default: as fast as possible)"},
    {"--shell", "WHERE", "open a robot's command shell while it runs: stdio, or tcp:PORT / tcp:HOST:PORT"},
    {"--shell-robot", "NAME", "the robot whose shell it is (default: the first)"},
    {"--token", "T", "the TCP shell's and the web view's token (default: a random one, printed)"},
    {"--view", "[ADDR:]PORT",
     "watch and drive the run in a browser at http://ADDR:PORT (default address 127.0.0.1; port 0: a free one)"},
    {"--view-robot", "NAME", "the robot the web view shows first (default: the first)"},
    {"--genome", "FILE", "replay a champion: the controller task gets this genome's weights (symb evolve)"},
    {"--controller", "NAME", "the task --genome replaces the weights of (default controller)"},
    {"--csv-every", "N", "record every N-th step in steps.csv (3D: poses.csv, joints.csv; default 1)"},
    {"--record", "FORMAT", "2D steps: csv, hdf5 (steps.h5), both or none (default: csv to 100 robots, hdf5 above)"},
    {"--record-every", "N", "record every N-th step (steps.csv, steps.h5; the same as --csv-every)"},
    {"--record-robots", "LIST", "2D: record only these robots' rows: names and ranges, e.g. t0..t99,t500"},
    {"--plugin", "PATH", "load a task-type plugin (a shared library; docs/plugins.md); may be repeated"},
    {"--bus", "KIND", "with --remote: the bus between the processes, dds (the only one; docs/bus.md)"},
    {"--remote", "NAMES",
     "2D: these robots' nodes run in other processes (symb serve --scenario S --robot NAME), in lockstep; "
     "comma-separated"},
    {"--domain", "N", "--remote: the DDS domain id, 0..232 (default 0)"},
    {"--prefix", "NAME", "--remote: the first name of every topic, rt/NAME/... (default symb)"},
    {"--lease", "D", "--remote: a robot process silent this long is lost (default 1s)"},
    {"--remote-wait", "D", "--remote: how long to wait for the robots' processes to answer (default 10s)"},
    {"--answer-wait", "D", "--remote: how long a step waits for a robot's answer before it is gone (default 2s)"},
    {"--print-hash", "", "print 'trajectory-hash: <16 hex digits>' on stdout"},
    {"--quiet", "", "no progress line and no summary"},
    {"--help", "", "this help"},
};

void print_run_help(std::ostream& out) {
  out << "Usage: " << kCommand << " SCENARIO [options]\n\n"
      << "Runs a scenario file (a world, robots and each robot's task graph; see docs/scenarios.md)\n"
      << "in this process, on the Enki simulator, headless. Each robot is a node running its task\n"
      << "graph against simulated IR sensor and wheel drivers, as the paper's Fig. 3 wires it:\n"
      << "ir (sensor task) -> controller -> wheels (actuator task). Virtual time by default: same\n"
      << "seed, same run, far faster than real time.\n\n"
      << "Options:\n"
      << describe_options(kOptions) << "\n"
      << "Writes trajectory.svg, steps.csv, summary.txt and syslog.txt into the output folder, with\n"
      << "probes.csv and probes/*.svg (controllers' internal state) and, for spiking controllers,\n"
      << "spikes/ (an AEDAT 2.0 file, a raster and the grown network per network task).\n"
      << "A 3D scenario (a MuJoCo world of docking modules) writes paths_top.svg, paths_side.svg,\n"
      << "poses.csv, joints.csv/.svg, docking.csv/.svg, topology.csv/.svg, world.xml (open it with\n"
      << "MuJoCo's simulate), summary.txt, syslog.txt and the probes (docs/run.md).\n"
      << "A shell needs --realtime or --speed (a virtual-time run is over before anyone could type);\n"
      << "with --shell and neither, --speed 1 is implied.\n"
      << "--view serves a page (the URL with its token is printed) showing the world, a robot's task\n"
      << "graph, probes and SysLog live, with a shell and pause, step and speed controls; with\n"
      << "--view and neither --realtime nor --speed, --speed 1 is implied (docs/view.md).\n"
      << "More than 100 robots: steps.h5 instead of steps.csv (--record), and density.svg, trails.svg,\n"
      << "robot_stats.csv and robot_stats.svg instead of trajectory.svg.\n"
      << "Ctrl-C stops the run early: the files are written for what was run (summary.txt says\n"
      << "where it stopped) and the exit status is 130.\n\n"
      << "--bus dds --remote NAMES runs those robots' nodes in other processes (symb serve --scenario\n"
      << "SCENARIO --robot NAME, started before or after), the world and the other robots here, in\n"
      << "lockstep: the same run as in one process (docs/bus.md). A robot whose process dies is reported,\n"
      << "its wheels stop and the run goes on; the exit status is then 1.\n\n"
      << "Example: symb run scenarios/maze.yaml --out out/maze\n";
}

std::string progress_text(const RunProgress& p, bool realtime) {
  std::string s = "run: " + fixed(p.simulated_seconds, 1) + " / " + fixed(p.total_seconds, 1) + " s " +
                  (realtime ? "real time" : "simulated") + " (" + fixed(100 * p.fraction(), 0) + "%)";
  if (!realtime && p.wall_seconds > 0) s += ", " + fixed(p.simulated_seconds / p.wall_seconds, 1) + "x real time";
  return s;
}

std::variant<ShellRequest, UsageError> parse_shell(std::string_view text) {
  ShellRequest r;
  if (text == "stdio") {
    r.kind = ShellRequest::Kind::kStdio;
    return r;
  }
  if (!text.starts_with("tcp:"))
    return UsageError{"--shell: expected stdio, tcp:PORT or tcp:HOST:PORT, not " + quote_arg(text)};
  if (auto e = parse_host_port("--shell", text.substr(4), text, r.host, r.port)) return *e;
  r.kind = ShellRequest::Kind::kTcp;
  return r;
}

// A champion file (symb evolve's champion.genome): a real genome's weights as a network task
// takes them.
std::variant<std::string, UsageError> read_genome_weights(std::string_view path) {
  std::ifstream in{std::string(path), std::ios::binary};
  if (!in) return UsageError{"--genome: cannot read " + quote_arg(path)};
  std::ostringstream text;
  text << in.rdbuf();
  auto genome = evo::parse_genome_text(text.str());
  if (!genome) return UsageError{"--genome: " + std::string(path) + ":" + genome.error()};
  const auto* real = std::get_if<evo::RealGenome>(&*genome);
  if (!real)
    return UsageError{"--genome: " + std::string(path) + " holds a " + evo::kind_name(evo::kind_of(*genome)) +
                      " genome; replay takes a real genome (network weights)"};
  return evo::weights_text(*real);
}

}  // namespace

int run_run_command(std::span<const std::string_view> args, const CliContext& ctx) {
  RunOptions options;
  auto split = scenario_command_args(args, kOptions, ctx, kCommand, print_run_help);
  if (const int* status = std::get_if<int>(&split)) return *status;
  const SplitArgs& parsed = std::get<SplitArgs>(split);
  const auto& opts = parsed.options;
  options.scenario_path = std::string(parsed.positional.front());

  bool print_hash = false, quiet = false, speed_given = false;
  std::string bus, remote_option;            // --bus, and the last option that is --remote's alone
  std::optional<std::uint32_t> every_given;  // --csv-every and --record-every, which must agree
  std::optional<std::string> token, shell_robot, genome_controller, view_robot;
  for (const ParsedOption& o : opts) {
    if (o.name == "--out") {
      if (o.value.empty()) return usage_error(ctx, kCommand, UsageError{"--out: empty folder name"});
      options.out_dir = o.value;
    } else if (o.name == "--seed") {
      auto v = parse_u64("--seed", o.value);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kCommand, *e);
      options.seed = std::get<std::uint64_t>(v);
    } else if (o.name == "--duration") {
      auto v = parse_duration("--duration", o.value, kMaxDuration);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kCommand, *e);
      options.duration = std::get<kernel::Duration>(v);
    } else if (o.name == "--realtime") {
      options.realtime = true;
    } else if (o.name == "--threads") {
      auto v = parse_count("--threads", o.value, 1, 64);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kCommand, *e);
      options.threads = static_cast<unsigned>(std::get<std::uint64_t>(v));
    } else if (o.name == "--speed") {
      auto v = parse_speed("--speed", o.value);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kCommand, *e);
      options.speed = std::get<double>(v);
      speed_given = true;
    } else if (o.name == "--shell") {
      auto v = parse_shell(o.value);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kCommand, *e);
      options.shell = std::get<ShellRequest>(v);
    } else if (o.name == "--view") {
      auto v = view::parse_view(o.value);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kCommand, *e);
      options.view = std::get<view::ViewRequest>(v);
    } else if (o.name == "--view-robot") {
      view_robot = o.value;
    } else if (o.name == "--shell-robot") {
      shell_robot = o.value;
    } else if (o.name == "--token") {
      token = o.value;
    } else if (o.name == "--genome") {
      auto weights = read_genome_weights(o.value);
      if (auto* e = std::get_if<UsageError>(&weights)) return usage_error(ctx, kCommand, *e);
      options.controller_weights = std::get<std::string>(weights);
    } else if (o.name == "--controller") {
      if (!os::is_valid_name(o.value))
        return usage_error(ctx, kCommand, UsageError{"--controller: " + quote_arg(o.value) + " cannot name a task"});
      genome_controller = o.value;
    } else if (o.name == "--csv-every" || o.name == "--record-every") {
      auto v = parse_count(o.name, o.value, 1, 1'000'000);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kCommand, *e);
      options.csv_every = static_cast<std::uint32_t>(std::get<std::uint64_t>(v));
      if (every_given && *every_given != options.csv_every)
        return usage_error(
            ctx, kCommand,
            UsageError{std::string(o.name) + " " + o.value + ": the step interval was given already as " +
                       std::to_string(*every_given) + " (--csv-every and --record-every are one setting)"});
      every_given = options.csv_every;
    } else if (o.name == "--record") {
      auto f = parse_record_format(o.value);
      if (!f) return usage_error(ctx, kCommand, UsageError{f.error()});
      options.record.format = *f;
    } else if (o.name == "--record-robots") {
      if (o.value.empty()) return usage_error(ctx, kCommand, UsageError{"--record-robots: empty list"});
      options.record.robots = o.value;
    } else if (o.name == "--plugin") {
      if (o.value.empty()) return usage_error(ctx, kCommand, UsageError{"--plugin: empty path"});
      options.plugins.emplace_back(o.value);
    } else if (o.name == "--bus") {
      if (o.value != "dds")
        return usage_error(ctx, kCommand, UsageError{"--bus " + quote_arg(o.value) + ": the only bus is dds"});
      bus = o.value;
    } else if (o.name == "--remote") {
      std::string_view rest = o.value;
      for (;;) {
        const auto comma = rest.find(',');
        const std::string name(rest.substr(0, comma));
        if (!os::is_valid_name(name))
          return usage_error(
              ctx, kCommand,
              UsageError{"--remote " + quote_arg(o.value) + ": " + quote_arg(name) + " cannot name a robot"});
        auto& names = options.remote.robots;
        if (std::find(names.begin(), names.end(), name) != names.end())
          return usage_error(ctx, kCommand, UsageError{"--remote " + quote_arg(o.value) + ": " + name + " twice"});
        names.push_back(name);
        if (comma == std::string_view::npos) break;
        rest = rest.substr(comma + 1);
      }
    } else if (o.name == "--domain") {
      auto v = parse_count("--domain", o.value, 0, 232);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kCommand, *e);
      options.remote.dds.domain = static_cast<std::uint32_t>(std::get<std::uint64_t>(v));
      remote_option = o.name;
    } else if (o.name == "--prefix") {
      if (!os::is_valid_name(o.value))
        return usage_error(ctx, kCommand, UsageError{"--prefix " + quote_arg(o.value) + ": not a name"});
      options.remote.dds.prefix = o.value;
      remote_option = o.name;
    } else if (o.name == "--lease" || o.name == "--remote-wait" || o.name == "--answer-wait") {
      auto v = parse_duration(o.name, o.value, std::chrono::hours(1));
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kCommand, *e);
      const kernel::Duration d = std::get<kernel::Duration>(v);
      if (d <= kernel::Duration{0})
        return usage_error(ctx, kCommand, UsageError{std::string(o.name) + " " + o.value + ": must be positive"});
      (o.name == "--lease"         ? options.remote.dds.lease
       : o.name == "--remote-wait" ? options.remote.wait
                                   : options.remote.answer_wait) = d;
      remote_option = o.name;
    } else if (o.name == "--print-hash") {
      print_hash = true;
    } else if (o.name == "--quiet") {
      quiet = true;
    }
  }
  if (!options.remote.robots.empty() && bus.empty())
    return usage_error(ctx, kCommand, UsageError{"--remote needs --bus dds (the bus between the processes)"});
  if (!bus.empty() && options.remote.robots.empty())
    return usage_error(ctx, kCommand, UsageError{"--bus " + bus + " carries remote robots: name them with --remote"});
  if (!remote_option.empty() && options.remote.robots.empty())
    return usage_error(ctx, kCommand, UsageError{remote_option + " is for --remote"});
  if (!options.remote.robots.empty() && options.realtime)
    return usage_error(ctx, kCommand,
                       UsageError{"--remote runs in lockstep with the world's virtual time, not with --realtime"});
  if (options.realtime && options.threads > 1)
    return usage_error(ctx, kCommand, UsageError{"--threads is for virtual time; --realtime runs a thread per task"});
  if (options.realtime && speed_given)
    return usage_error(ctx, kCommand, UsageError{"--speed is for virtual time; --realtime runs at the wall clock"});
  const bool has_shell = options.shell.kind != ShellRequest::Kind::kNone;
  if (shell_robot && !has_shell) return usage_error(ctx, kCommand, UsageError{"--shell-robot needs --shell"});
  if (view_robot && !options.view.on) return usage_error(ctx, kCommand, UsageError{"--view-robot needs --view"});
  if (token && options.shell.kind != ShellRequest::Kind::kTcp && !options.view.on)
    return usage_error(ctx, kCommand, UsageError{"--token is for --shell tcp:... and --view"});
  if (genome_controller && !options.controller_weights)
    return usage_error(ctx, kCommand, UsageError{"--controller names the task --genome replays into: give --genome"});
  if (genome_controller) options.genome_controller = *genome_controller;
  if (shell_robot) options.shell.robot = *shell_robot;
  if (token) options.shell.token = options.view.token = *token;
  if (view_robot) options.view.robot = *view_robot;
  if ((has_shell || options.view.on) && !options.realtime && !speed_given) options.speed = 1.0;
  // A stdio shell owns stdout; the progress line and the summary then stay off it.
  if (options.shell.kind == ShellRequest::Kind::kStdio) quiet = true;

  ProgressLine progress(ctx.err, !quiet, ctx.err_is_terminal);
  options.on_progress = [&](const RunProgress& p) {
    progress.update(p.fraction(), progress_text(p, options.realtime));
  };
  options.on_notice = [&ctx](const std::string& line) { ctx.err << line << "\n" << std::flush; };
  // The default folder needs the scenario's name, which only the run knows.
  if (!options.out_dir) options.out_under = std::filesystem::path("out");

  // Ctrl-C (or SIGTERM) ends the run between two slices; what was run is written, as symb sim
  // does, and the exit status says it was interrupted.
  InterruptFlag interrupt;
  options.stop_requested = [&interrupt] { return interrupt.raised(); };
  auto result = run_scenario(options);
  if (!result) {
    progress.finish("run: stopped");
    ctx.err << kCommand << ": " << result.error() << "\n";
    return kExitFailure;
  }
  const RunResult& r = *result;
  progress.finish(progress_text(RunProgress{r.simulated_seconds,
                                            r.interrupted ? r.planned_seconds : r.simulated_seconds, r.wall_seconds},
                                r.realtime) +
                  (r.interrupted ? ": interrupted" : ""));
  if (r.interrupted)
    ctx.err << kCommand << ": interrupted at " << fixed(r.simulated_seconds, 1) << " s of "
            << fixed(r.planned_seconds, 1) << " s; the results so far are written\n";
  if (print_hash) ctx.out << "trajectory-hash: " << hex64(r.trajectory_hash) << "\n";
  if (!quiet && !print_hash) {
    ctx.out << "run: " << r.scenario << ", seed " << r.seed << ", " << r.robots.size() << " robot"
            << (r.robots.size() == 1 ? "" : "s") << ", " << fixed(r.simulated_seconds, 1) << " s "
            << (r.realtime ? "on the wall clock"
                           : "simulated in " + fixed(r.wall_seconds, 2) + " s (" + fixed(r.real_time_factor, 0) +
                                 "x real time)")
            << "\n";
    const std::size_t shown = std::min<std::size_t>(r.robots.size(), 10);
    if (!r.organism.empty()) ctx.out << "  organism: " << r.organism << "\n";
    for (std::size_t i = 0; i < shown; ++i) {
      const RobotSummary& s = r.robots[i];
      ctx.out << "  " << s.name << ": " << fixed(s.distance / 100.0, 2) << " m travelled";
      if (r.organism.empty())
        ctx.out << ", " << s.contact_events << " contacts (" << s.contact_steps << " steps touching), moving "
                << fixed(s.moving_seconds, 1) << " s";
      ctx.out << "\n";
    }
    if (shown < r.robots.size()) ctx.out << "  ... " << r.robots.size() - shown << " more in summary.txt\n";
  }
  if (!r.files.empty() && !(print_hash && quiet)) {
    std::ostream& where = print_hash || options.shell.kind == ShellRequest::Kind::kStdio ? ctx.err : ctx.out;
    where << "results in " << r.out_dir.string() << "/\n";
    for (const auto& f : r.files) where << "  " << f.string() << "\n";
    where << std::flush;
  }
  if (r.remote_gone > 0) {
    ctx.err << kCommand << ": " << r.remote_gone << " remote robot" << (r.remote_gone == 1 ? "" : "s")
            << " gone during the run (stopped there; summary.txt says which, when and why)\n";
    if (!r.interrupted) return kExitFailure;
  }
  return r.interrupted ? kExitInterrupted : kExitOk;
}

}  // namespace symb::apps::run
