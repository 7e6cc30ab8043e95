#include "symb/apps/swarm/swarm_command.hpp"

#include <cstdio>
#include <string>

#include "symb/apps/progress_line.hpp"
#include "symb/apps/swarm/swarm_demo.hpp"

namespace symb::apps {

namespace {

constexpr std::string_view kCommand = "symb demo swarm";
constexpr std::string_view kDefaultOut = "out/swarm";

constexpr OptionSpec kOptions[] = {
    {"--nodes", "N", "number of robots, 1 to 10000 (default 100; at most 250 with --realtime)"},
    {"--seed", "S", "run seed, unsigned 64-bit, decimal or 0x-hex (default 1)"},
    {"--duration", "D", "simulated time with a unit: 60s, 500ms, 2min, 1h (default 60s)"},
    {"--out", "DIR", "output folder (default out/swarm)"},
    {"--realtime", "", "run on OS threads against the wall clock (not deterministic)"},
    {"--shell-port", "PORT", "with --realtime: open robot 0's command shell on 127.0.0.1:PORT (0: any free port)"},
    {"--print-hash", "", "print only 'trace-hash: <16 hex digits>' on stdout; files only with --out"},
    {"--quiet", "", "no progress line and no summary"},
    {"--help", "", "this help"},
};

void print_swarm_help(std::ostream& out) {
  out << "Usage: " << kCommand << " [options]\n\n"
      << "N robots wander in a square walled arena. Each robot is its own node (own seed, own\n"
      << "SysLog) running the task graph kinematics -> proximity -> wander -> kinematics, made\n"
      << "by name from a task-type registry and wired by hooks. All nodes share one deterministic\n"
      << "virtual-time executor (same seed, same trace hash), or OS threads with --realtime.\n\n"
      << "Options:\n"
      << describe_options(kOptions) << "\n"
      << "Writes trajectories.svg, summary.txt and syslog.txt (node 0's log) into the output folder.\n";
}

std::string progress_text(const SwarmProgress& p, bool realtime) {
  std::string s = "swarm: " + fixed(p.simulated_seconds, 1) + " / " + fixed(p.total_seconds, 1) + " s " +
                  (realtime ? "real time" : "simulated") + " (" + fixed(100 * p.fraction(), 0) + "%)";
  if (!realtime && p.wall_seconds > 0) s += ", " + fixed(p.simulated_seconds / p.wall_seconds, 1) + "x real time";
  return s;
}

}  // namespace

int run_swarm_command(std::span<const std::string_view> args, const CliContext& ctx) {
  auto parsed = parse_options(args, kOptions);
  if (auto* e = std::get_if<UsageError>(&parsed)) return usage_error(ctx, kCommand, *e);

  SwarmOptions options;
  std::optional<std::string> out_dir;
  bool print_hash = false, quiet = false;
  for (const ParsedOption& o : std::get<std::vector<ParsedOption>>(parsed)) {
    if (o.name == "--help") {
      print_swarm_help(ctx.out);
      return kExitOk;
    }
  }
  for (const ParsedOption& o : std::get<std::vector<ParsedOption>>(parsed)) {
    if (o.name == "--nodes") {
      auto v = parse_count("--nodes", o.value, 1, kMaxSwarmNodes);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kCommand, *e);
      options.nodes = static_cast<std::size_t>(std::get<std::uint64_t>(v));
    } else if (o.name == "--seed") {
      auto v = parse_u64("--seed", o.value);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kCommand, *e);
      options.seed = std::get<std::uint64_t>(v);
    } else if (o.name == "--duration") {
      auto v = parse_duration("--duration", o.value, kMaxSwarmDuration);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kCommand, *e);
      options.duration = std::get<kernel::Duration>(v);
    } else if (o.name == "--out") {
      out_dir = o.value;
    } else if (o.name == "--realtime") {
      options.realtime = true;
    } else if (o.name == "--shell-port") {
      auto v = parse_count("--shell-port", o.value, 0, 65535);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kCommand, *e);
      options.shell_port = static_cast<std::uint16_t>(std::get<std::uint64_t>(v));
    } else if (o.name == "--print-hash") {
      print_hash = true;
    } else if (o.name == "--quiet") {
      quiet = true;
    }
  }
  if (options.shell_port && !options.realtime)
    return usage_error(
        ctx, kCommand,
        UsageError{"--shell-port needs --realtime: a virtual-time run is over before anyone could type"});
  options.on_shell = [&ctx](const std::string& where, const std::string& token) {
    ctx.err << "shell: symb shell --tcp " << where << (token.empty() ? "" : " --token " + token) << "\n";
  };
  if (options.realtime && options.nodes > kMaxRealtimeSwarmNodes)
    return usage_error(
        ctx, kCommand,
        UsageError{"--nodes: with --realtime (four OS threads per robot) at most " +
                   std::to_string(kMaxRealtimeSwarmNodes) + " robots, not " + std::to_string(options.nodes)});
  // --print-hash keeps stdout for the hash alone and, so that scripts and tests can run it side by
  // side, writes files only where it is explicitly told to.
  if (out_dir)
    options.out_dir = *out_dir;
  else if (!print_hash)
    options.out_dir = std::string(kDefaultOut);

  ProgressLine progress(ctx.err, !quiet, ctx.err_is_terminal);
  options.on_progress = [&](const SwarmProgress& p) {
    progress.update(p.fraction(), progress_text(p, options.realtime));
  };
  auto result = run_swarm(options);
  if (!result) {
    progress.finish("swarm: stopped");
    ctx.err << kCommand << ": " << result.error() << "\n";
    return kExitFailure;
  }
  const SwarmResult& r = *result;
  progress.finish(progress_text(SwarmProgress{r.simulated_seconds, r.simulated_seconds, r.wall_seconds}, r.realtime));

  if (print_hash) ctx.out << "trace-hash: " << hex64(r.trace_hash) << "\n" << std::flush;
  if (!print_hash && !quiet) {
    ctx.out << "swarm: " << r.nodes << " robots, seed " << r.seed << ", " << fixed(r.simulated_seconds, 1) << " s "
            << (r.realtime ? "on the wall clock"
                           : "simulated in " + fixed(r.wall_seconds, 2) + " s (" + fixed(r.real_time_factor, 1) +
                                 "x real time)")
            << "\n"
            << "messages: " << r.traffic.delivered << " delivered, " << r.traffic.dropped() << " dropped; trace hash "
            << hex64(r.trace_hash) << (r.realtime ? " (not deterministic under --realtime)" : "") << "\n";
  }
  if (!r.files.empty()) {
    // The hash owns stdout under --print-hash; the folder is then news for the person, on stderr.
    std::ostream& where = print_hash ? ctx.err : ctx.out;
    if (!(print_hash && quiet)) {
      where << "results in " << r.out_dir.string() << "/\n";
      for (const auto& f : r.files) where << "  " << f.string() << "\n";
      where << std::flush;
    }
  }
  return kExitOk;
}

}  // namespace symb::apps
