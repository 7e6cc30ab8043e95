#include "symb/apps/serve/serve_command.hpp"

#include <chrono>
#include <fstream>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "symb/apps/run/probe_recorder.hpp"
#include "symb/control/control_task_types.hpp"
#include "symb/io/dds/dds_bus.hpp"
#include "symb/kernel/thread_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/os/task_type_registry.hpp"
#include "symb/shell/shell.hpp"

namespace symb::apps::serve {
namespace {

using namespace std::chrono_literals;

constexpr std::string_view kCommand = "symb serve";

constexpr OptionSpec kServeOptions[] = {
    {"--node", "NAME", "this process's node (required)"},
    {"--bus", "KIND", "the bus between processes: dds (the default and only one)"},
    {"--domain", "N", "DDS domain id, 0..232 (default 0)"},
    {"--prefix", "NAME", "first name of every topic, rt/NAME/... (default symb)"},
    {"--lease", "DURATION", "a sender silent this long is reported lost (default 1s)"},
    {"--exec", "LINE", "a shell line on this node, in order (repeatable): create TYPE NAME ..."},
    {"--hook", "FROM>TO[:PORT]", "a remote hook node/task>node/task, declared alike by every process (repeatable)"},
    {"--duration", "DURATION", "how long to run once linked (default 10s)"},
    {"--link-timeout", "DURATION", "how long to wait for the peers before running anyway (default 10s)"},
    {"--seed", "N", "the node's seed (default 1)"},
    {"--probes", "FILE", "write every probe sample of the node's tasks to FILE (CSV, as symb run's probes.csv)"},
    {"--scenario", "FILE",
     "serve one robot of this scenario's world, run by symb run --bus dds --remote (docs/bus.md)"},
    {"--robot", "NAME", "with --scenario: the robot whose node this process runs"},
    {"--wait", "DURATION", "with --scenario: how long to wait for the world (default 60s)"},
    {"--plugin", "PATH", "with --scenario: a task-type plugin, as symb run --plugin (repeatable)"},
    {"--help", "", "print this help"},
};

void print_serve_help(std::ostream& out) {
  out << "Usage: symb serve --node NAME [options]\n\n"
      << "One node in its own process, joined to the nodes of other processes over Cyclone DDS\n"
      << "(docs/bus.md). Every process declares the same --hook list and builds the ends it holds.\n\n"
      << "Options:\n"
      << describe_options(kServeOptions) << "\n"
      << "With --scenario and --robot it serves one robot of a split world instead: the robot's node,\n"
      << "built as symb run builds it, answers the world of `symb run SCENARIO --bus dds --remote NAME`\n"
      << "in lockstep (the same --domain and --prefix), until that run ends.\n"
      << "\nExample (two terminals):\n"
      << "  symb serve --node m1 --exec 'create oscillator osc id=0 coupling=4' --hook 'm1/osc>m2/osc:1' "
         "--hook 'm2/osc>m1/osc:1'\n"
      << "  symb serve --node m2 --exec 'create oscillator osc id=1 coupling=4' --hook 'm1/osc>m2/osc:1' "
         "--hook 'm2/osc>m1/osc:1'\n";
}

struct HookSpec {
  std::string from, to;
  int port = -1;
};

std::variant<HookSpec, UsageError> parse_hook(std::string_view text) {
  const auto arrow = text.find('>');
  if (arrow == std::string_view::npos)
    return UsageError{"--hook " + quote_arg(text) + ": expected SENDER>RECEIVER[:PORT]"};
  HookSpec h;
  h.from = std::string(text.substr(0, arrow));
  std::string_view rest = text.substr(arrow + 1);
  if (const auto colon = rest.find(':'); colon != std::string_view::npos) {
    auto port = parse_count("--hook port", rest.substr(colon + 1), 0, 65535);
    if (auto* e = std::get_if<UsageError>(&port)) return *e;
    h.port = static_cast<int>(std::get<std::uint64_t>(port));
    rest = rest.substr(0, colon);
  }
  h.to = std::string(rest);
  return h;
}

}  // namespace

int run_serve_command(std::span<const std::string_view> args, const CliContext& ctx) {
  auto split = split_args(args, kServeOptions, 0);
  if (auto* e = std::get_if<UsageError>(&split)) return usage_error(ctx, kCommand, *e);
  const SplitArgs& a = std::get<SplitArgs>(split);
  if (a.help) {
    print_serve_help(ctx.out);
    return kExitOk;
  }
  std::string name;
  io::DdsBusOptions bus_options;
  std::vector<std::string> lines;
  std::vector<HookSpec> hooks;
  kernel::Duration duration = 10s, link_timeout = 10s;
  std::uint64_t seed = 1;
  std::string probes_path;
  ServeRobotArgs robot_args;
  std::string node_option;  // the last option that is --node's alone
  constexpr kernel::Duration kMax = std::chrono::hours(24 * 365);
  for (const ParsedOption& o : a.options) {
    if (o.name == "--exec" || o.name == "--hook" || o.name == "--duration" || o.name == "--link-timeout" ||
        o.name == "--probes" || o.name == "--seed" || o.name == "--node")
      node_option = o.name;
    if (o.name == "--scenario") {
      if (o.value.empty()) return usage_error(ctx, kCommand, UsageError{"--scenario: empty file name"});
      robot_args.scenario = o.value;
    } else if (o.name == "--robot") {
      if (!os::is_valid_name(o.value))
        return usage_error(ctx, kCommand, UsageError{"--robot " + quote_arg(o.value) + ": cannot name a robot"});
      robot_args.robot = o.value;
    } else if (o.name == "--wait") {
      auto v = parse_duration("--wait", o.value, kMax);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kCommand, *e);
      robot_args.wait = std::get<kernel::Duration>(v);
    } else if (o.name == "--plugin") {
      if (o.value.empty()) return usage_error(ctx, kCommand, UsageError{"--plugin: empty path"});
      robot_args.plugins.push_back(o.value);
    } else if (o.name == "--node") {
      name = o.value;
    } else if (o.name == "--bus") {
      if (o.value != "dds") return usage_error(ctx, kCommand, UsageError{"--bus " + quote_arg(o.value) + ": only dds"});
    } else if (o.name == "--domain") {
      auto v = parse_count("--domain", o.value, 0, 232);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kCommand, *e);
      bus_options.domain = static_cast<std::uint32_t>(std::get<std::uint64_t>(v));
    } else if (o.name == "--prefix") {
      if (o.value.empty()) return usage_error(ctx, kCommand, UsageError{"--prefix: empty"});
      bus_options.prefix = o.value;
    } else if (o.name == "--lease" || o.name == "--duration" || o.name == "--link-timeout") {
      auto v = parse_duration(o.name, o.value, kMax);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kCommand, *e);
      (o.name == "--lease"      ? bus_options.lease
       : o.name == "--duration" ? duration
                                : link_timeout) = std::get<kernel::Duration>(v);
    } else if (o.name == "--exec") {
      lines.push_back(o.value);
    } else if (o.name == "--hook") {
      auto h = parse_hook(o.value);
      if (auto* e = std::get_if<UsageError>(&h)) return usage_error(ctx, kCommand, *e);
      hooks.push_back(std::get<HookSpec>(h));
    } else if (o.name == "--probes") {
      if (o.value.empty()) return usage_error(ctx, kCommand, UsageError{"--probes: empty file name"});
      probes_path = o.value;
    } else if (o.name == "--seed") {
      auto v = parse_u64("--seed", o.value);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kCommand, *e);
      seed = std::get<std::uint64_t>(v);
    }
  }
  if (!robot_args.scenario.empty() || !robot_args.robot.empty()) {
    if (robot_args.scenario.empty()) return usage_error(ctx, kCommand, UsageError{"--robot needs --scenario FILE"});
    if (robot_args.robot.empty()) return usage_error(ctx, kCommand, UsageError{"--scenario needs --robot NAME"});
    if (!node_option.empty())
      return usage_error(ctx, kCommand,
                         UsageError{node_option + " is for --node; a scenario's robot is built from the scenario"});
    robot_args.dds = {bus_options.domain, bus_options.prefix, bus_options.lease};
    return run_serve_robot(robot_args, ctx);
  }
  if (!robot_args.plugins.empty()) return usage_error(ctx, kCommand, UsageError{"--plugin is for --scenario"});
  if (name.empty())
    return usage_error(ctx, kCommand, UsageError{"--node NAME is required (or --scenario FILE --robot NAME)"});

  os::TaskTypeRegistry types;
  if (auto st = control::register_control_task_types(types, {}); !st) {
    ctx.err << kCommand << ": " << st.error() << "\n";
    return kExitFailure;
  }
  kernel::ThreadExecutor executor;
  os::Node node(executor, {.name = name, .seed = seed, .types = &types});
  auto made = io::DdsBus::create({&node}, bus_options);
  if (!made) {
    ctx.err << kCommand << ": " << made.error() << "\n";
    return kExitFailure;
  }
  io::DdsBus& bus = **made;
  std::ofstream probes_file;
  std::optional<run::ProbeRecorder> probes;
  if (!probes_path.empty()) {
    probes_file.open(probes_path, std::ios::binary | std::ios::trunc);
    if (!probes_file) {
      ctx.err << kCommand << ": cannot write " << probes_path << "\n";
      return kExitFailure;
    }
    probes.emplace(&probes_file);
    node.set_probe_sink(probes->sink());
  }
  struct ProbeSinkGuard {  // the sink points at `probes`, which goes before the node
    os::Node& n;
    ~ProbeSinkGuard() { n.set_probe_sink({}); }
  } probe_sink_guard{node};
  shell::Shell::Options shell_options;
  shell_options.remote_hook = [&bus](const std::string& sender, const std::string& receiver,
                                     const os::HookOptions& o) -> kernel::Result<std::string> {
    auto id = bus.hook(sender, receiver, o);
    if (!id) return kernel::Error{id.error()};
    return "remote hook " + std::to_string(id->value) + ": " + sender + " -> " + receiver + " (over DDS)\n";
  };
  shell_options.remote_hooks = [&bus] { return bus.listing(); };
  shell::Shell shell(node, shell_options);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const shell::Reply r = shell.execute(lines[i]);
    if (!r.ok) {
      ctx.err << kCommand << ": --exec " << (i + 1) << " " << quote_arg(lines[i]) << ": " << r.text;
      return kExitFailure;
    }
  }
  for (const HookSpec& h : hooks) {
    const bool mine = h.from.starts_with(name + "/") || h.to.starts_with(name + "/");
    if (!mine) continue;  // between two other processes
    auto id = bus.hook(h.from, h.to, {.port = h.port});
    if (!id) {
      ctx.err << kCommand << ": --hook " << h.from << ">" << h.to << ": " << id.error() << "\n";
      return kExitFailure;
    }
  }
  const auto started = std::chrono::steady_clock::now();
  const bool linked = bus.wait_linked(link_timeout);
  const double link_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  ctx.out << "serve " << name << ": " << (linked ? "linked" : "not every peer found") << " after " << fixed(link_s, 3)
          << " s\n"
          << std::flush;
  // Tasks created --suspended start now, so nothing they send is dropped while no peer listens.
  for (const os::TaskInfo& t : node.tasks())
    if (t.state == os::TaskState::kCreated) (void)node.start(t.id);
  std::this_thread::sleep_for(duration);
  // Stop sending, let the readers acknowledge what was written, then wait for the peers' senders
  // to finish theirs (they leave, or are lost after the lease) before the books are read.
  for (const os::TaskInfo& t : node.tasks())
    if (!t.name.starts_with("dds_")) (void)node.suspend(t.id);
  const bool flushed = bus.flush(5s);
  bus.finish_sending();
  const auto until = std::chrono::steady_clock::now() + 5s;
  for (;;) {
    bool settled = true;
    for (const io::RemoteHookInfo& h : bus.hooks())
      if (h.receiver_module != io::kRemoteEnd && h.state == io::LinkState::kUp) settled = false;
    if (settled || std::chrono::steady_clock::now() > until) break;
    std::this_thread::sleep_for(5ms);
  }
  ctx.out << "serve " << name << ": " << (flushed ? "flushed" : "not every write acknowledged") << "\n"
          << bus.listing();
  for (const os::LogEntry& e : node.log().since(0))
    if (e.level >= os::LogLevel::kWarn) ctx.out << "log: " << e.source << ": " << e.text << "\n";
  return kExitOk;
}

}  // namespace symb::apps::serve
