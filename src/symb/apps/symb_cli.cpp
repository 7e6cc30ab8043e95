#include "symb/apps/symb_cli.hpp"

#include <array>

#include "symb/apps/evolve/evolve_command.hpp"
#include "symb/apps/hil/hil_commands.hpp"
#include "symb/apps/run/run_command.hpp"
#include "symb/apps/serve/serve_command.hpp"
#include "symb/apps/shell_client.hpp"
#include "symb/apps/swarm/swarm_command.hpp"

#ifndef SYMB_VERSION
#define SYMB_VERSION "unknown"
#endif

namespace symb::apps {

namespace {

constexpr std::string_view kCommands[] = {"run",  "evolve", "sim",     "board", "link",
                                          "demo", "shell",  "version", "help",  "serve"};
constexpr std::string_view kDemos[] = {"swarm"};

void print_symb_help(std::ostream& out) {
  out << "symb " << symb_version()
      << " - Symbricator: bio-inspired robot control and evolution (SymbricatorRTOS re-implemented)\n\n"
      << "Usage: symb <command> [options]\n\n"
      << "Commands:\n"
      << "  run SCENARIO [options]  run a scenario file in-process (the main job: scenarios/maze.yaml)\n"
      << "  evolve SCENARIO [options]  run an evolution experiment headless (scenarios/evolve_maze.yaml)\n"
      << "  sim SCENARIO --serial PATH   hardware in the loop: the simulator side (docs/hil.md)\n"
      << "  board SCENARIO --serial PATH [--shell PATH]   ... the board side: one robot's tasks\n"
      << "  link [--dir DIR]        ... the serial lines between them, from pseudo-terminals\n"
      << "  board SCENARIO --robot aseba:tcp:HOST:PORT | aseba:serial:PATH\n"
      << "                          a real Thymio II, or Aseba Playground's, over Aseba (docs/thymio.md)\n"
      << "  serve --node NAME [options]\n"
      << "                          one node in its own process, joined to others over DDS (docs/bus.md)\n"
      << "  demo <name> [options]   run a built-in demo (symb demo --help lists them)\n"
      << "  shell --tcp HOST:PORT | --serial PATH\n"
      << "                          open a running node's command shell (like telnet or picocom)\n"
      << "  version                 print the version\n"
      << "  help                    print this help\n\n"
      << "Run 'symb <command> --help' for a command's options.\n"
      << "Exit codes: 0 done, 1 failed while running, 2 bad command line.\n";
}

void print_demo_help(std::ostream& out) {
  out << "Usage: symb demo <name> [options]\n\n"
      << "Demos:\n"
      << "  swarm    robots wandering in a walled arena, one node each, on one virtual-time\n"
      << "           executor; writes trajectories.svg, summary.txt, syslog.txt\n\n"
      << "Run 'symb demo <name> --help' for a demo's options.\n";
}

int run_demo(std::span<const std::string_view> args, const CliContext& ctx) {
  if (args.empty()) return usage_error(ctx, "symb demo", UsageError{"missing demo name (available: swarm)"});
  const std::string_view name = args.front();
  if (name == "-h" || name == "--help") {
    print_demo_help(ctx.out);
    return kExitOk;
  }
  if (name == "swarm") return run_swarm_command(args.subspan(1), ctx);
  if (name.starts_with("-"))
    return usage_error(ctx, "symb demo",
                       UsageError{"unknown option " + quote_arg(name) +
                                  did_you_mean(name, std::array<std::string_view, 1>{"--help"})});
  return usage_error(
      ctx, "symb demo",
      UsageError{"unknown demo " + quote_arg(name) + did_you_mean(name, kDemos) + " (available: swarm)"});
}

}  // namespace

std::string_view symb_version() { return SYMB_VERSION; }

int run_symb(std::span<const std::string_view> args, const CliContext& ctx) {
  if (args.empty()) {
    print_symb_help(ctx.err);
    ctx.err << "\nsymb: missing command\n";
    return kExitUsage;
  }
  const std::string_view command = args.front();
  const auto rest = args.subspan(1);
  if (command == "-h" || command == "--help" || command == "help") {
    if (!rest.empty()) return usage_error(ctx, "symb", UsageError{"unexpected argument " + quote_arg(rest.front())});
    print_symb_help(ctx.out);
    return kExitOk;
  }
  if (command == "version" || command == "--version") {
    if (!rest.empty())
      return usage_error(ctx, "symb version", UsageError{"unexpected argument " + quote_arg(rest.front())});
    ctx.out << "symb " << symb_version() << "\n";
    return kExitOk;
  }
  if (command == "run") return run::run_run_command(rest, ctx);
  if (command == "evolve") return evolve::run_evolve_command(rest, ctx);
  if (command == "sim") return hil::run_sim_command(rest, ctx);
  if (command == "board") return hil::run_board_command(rest, ctx);
  if (command == "link") return hil::run_link_command(rest, ctx);
  if (command == "demo") return run_demo(rest, ctx);
  if (command == "serve") return serve::run_serve_command(rest, ctx);
  if (command == "shell") {
    auto parsed = parse_shell_client_args(rest);
    if (auto* e = std::get_if<UsageError>(&parsed)) return usage_error(ctx, "symb shell", *e);
    const auto& o = std::get<ShellClientOptions>(parsed);
    if (o.help) {
      ctx.out << shell_client_help();
      return kExitOk;
    }
    return run_shell_client(o);
  }
  if (command.starts_with("-")) {
    constexpr std::string_view kTopOptions[] = {"--help", "--version"};
    return usage_error(ctx, "symb",
                       UsageError{"unknown option " + quote_arg(command) + did_you_mean(command, kTopOptions)});
  }
  return usage_error(ctx, "symb",
                     UsageError{"unknown command " + quote_arg(command) + did_you_mean(command, kCommands)});
}

}  // namespace symb::apps
