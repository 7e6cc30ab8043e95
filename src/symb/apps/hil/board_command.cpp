// `symb board SCENARIO --serial PATH`: the board side of hardware-in-the-loop, the paper's
// evaluation board. One robot's control system from the scenario runs here on OS threads; its
// IR sensor and wheel tasks talk to the simulator over the serial line, and its command shell
// listens on a second line. With --lockstep the node runs on a clock the simulator's frames drive
// instead (sim::HilRobotBoard), as a 3D board's always does.
#include <thread>

#include "symb/apps/hil/hil_commands.hpp"
#include "symb/apps/hil/hil_common.hpp"
#include "symb/apps/view/view_request.hpp"
#include "symb/io/serial_port.hpp"
#include "symb/kernel/thread_executor.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/shell/shell_task.hpp"
#include "symb/sim/board_link.hpp"
#include "symb/sim/hil_robot_board.hpp"
#include "symb/sim/playground_world.hpp"
#include "symb/sim/robot_system.hpp"
#include "symb/sim/scenario.hpp"

namespace symb::apps::hil {

namespace {

using namespace std::chrono_literals;

constexpr std::string_view kBoardCommand = "symb board";

constexpr OptionSpec kBoardOptions[] = {
    {"--serial", "PATH", "the data line to the simulator"},
    {"--shell", "PATH", "a second serial line for the command shell (symb shell --serial ...)"},
    {"--robot", "NAME", "the scenario's robot this board runs (default: the first; 3D: required)"},
    {"--lockstep", "", "2D: the node's clock follows the simulator's frames, not the wall clock (3D always)"},
    {"--dds", "", "3D scenarios: reach the simulator over DDS (symb sim --dds) instead of --serial"},
    {"--domain", "N", "--dds: the DDS domain id, 0..232 (default 0)"},
    {"--prefix", "NAME", "--dds: the first name of every topic, rt/NAME/... (default symb)"},
    {"--lease", "D", "--dds: a simulator silent this long is lost (default 1s)"},
    {"--playground", "OUT", "write the scenario's world as an Aseba Playground file and exit (docs/thymio.md)"},
    {"--port", "N", "--playground: the first robot's port (default 33333)"},
    {"--speed-scale", "X", "aseba: Thymio motor target per wheel unit (default 1 on tcp, 0.83 on serial)"},
    {"--duration", "D", "stop after this long (default: at Ctrl-C)"},
    {"--seed", "S", "the run's seed, for the node's random streams (default: the scenario's)"},
    {"--stats-every", "D", "print the link statistics this often (default 5s)"},
    {"--quiet", "", "print only the final statistics, not the robot's log"},
    {"--view", "[ADDR:]PORT", "watch the robot's task graph, probes, log and shell in a browser (docs/view.md)"},
    {"--token", "T", "the web view's token (default: a random one, printed)"},
    {"--help", "", "this help"},
};

void print_board_help(std::ostream& out) {
  out << "Usage: " << kBoardCommand << " SCENARIO --serial PATH [options]\n\n"
      << "The board side of hardware-in-the-loop (docs/hil.md): builds one robot's control system\n"
      << "from the scenario and runs it on OS threads at wall-clock time, with its device tasks on\n"
      << "the serial line: link (frames) -> ir -> the scenario's controller -> wheels -> link. The\n"
      << "simulator (symb sim) sends IR frames and reads the wheel speeds back. The robot's log and\n"
      << "the link statistics (frames good, bad, missed) are printed as it runs.\n\n"
      << "With --robot aseba:tcp:HOST:PORT (Aseba Playground) or aseba:serial:PATH (a Thymio II on USB)\n"
      << "the scenario's first robot runs against that Thymio over the Aseba protocol instead of a\n"
      << "simulator; --serial is then not needed (docs/thymio.md).\n\n"
      << "Options:\n"
      << describe_options(kBoardOptions) << "\n"
      << "With --lockstep the node's clock follows the simulator's frames: each IR frame runs it up to\n"
      << "the world's next step and the wheels' output then is the answer, so every act of the node falls\n"
      << "where it falls in process; with `symb sim --lockstep` the run is `symb run`'s, bit for bit,\n"
      << "however busy the machine.\n\n"
      << "Runs until Ctrl-C (or --duration); it keeps running when the link goes silent, and when the\n"
      << "serial device goes away it reopens the path with backoff (100 ms doubling to 2 s). It exits\n"
      << "1 when the line was down at the end (a dead link), with how long it was down.\n";
}

struct BoardLockstepArgs {
  std::shared_ptr<io::SerialPort> port, shell_port;
  std::string serial, shell_path;
  std::optional<std::uint64_t> seed;
  std::optional<kernel::Duration> duration;
  kernel::Duration stats_every{0};
  bool quiet = false;
  view::ViewRequest view;
};

// The 2D board on the simulator's frames: the robot's RobotSystem over HilRobotBoard's devices on
// a virtual-time executor that serve() drives.
int run_board_lockstep(const sim::Scenario& sc, std::size_t index, const BoardLockstepArgs& a, const CliContext& ctx) {
  const sim::RobotSpec& spec = sc.robots[index];
  kernel::VirtualTimeExecutor ex;
  sim::FrameClockBoardOptions bo;
  bo.control_period = sc.control_period;
  bo.on_event = [&ctx, &spec](const std::string& text) {
    ctx.err << "board " << spec.name << ": " << text << "\n" << std::flush;
  };
  sim::HilRobotBoard board(ex, a.port, bo);
  sim::RobotSystemOptions ro;
  ro.control_period = sc.control_period;
  ro.seed = sim::robot_node_seed(a.seed.value_or(sc.seed), index);
  ro.read_program = sim::file_program_reader(sc.base_dir);
  auto built = sim::RobotSystem::build(ex, spec, board.devices(), ro);
  if (!built) {
    ctx.err << kBoardCommand << ": " << built.error() << "\n";
    return kExitFailure;
  }
  std::unique_ptr<sim::RobotSystem> system = std::move(built).value();
  FrameBoardRun run;
  run.board = &board;
  run.executor = &ex;
  run.node = &system->node();
  run.devices = board.device_list();
  run.robot = spec.name;
  run.scenario = sc.name;
  run.where = a.serial;
  run.data = a.port;
  run.shell_port = a.shell_port;
  run.shell_path = a.shell_path;
  run.quiet = a.quiet;
  run.view = a.view;
  run.stats = [&board] { return sim::describe(board.stats()); };
  run.duration = a.duration;
  run.stats_every = a.stats_every;
  auto ran = run_frame_board(run, ctx);
  if (!ran) {
    ctx.err << kBoardCommand << ": " << ran.error() << "\n";
    return kExitFailure;
  }
  const FrameBoardEnd& end = *ran;
  const sim::HilRobotBoardStats s = board.stats();
  ctx.out << "board: " << sim::describe(s) << "\n" << frame_board_stats_line(s, end) << "\n";
  system.reset();
  a.port->close();
  if (a.shell_port) a.shell_port->close();
  // A dead link is a failed run: the serial line was down when the board stopped.
  if (const std::string failure = frame_board_failure(end, a.serial); !failure.empty()) {
    ctx.err << kBoardCommand << ": " << failure << "\n";
    return kExitFailure;
  }
  return kExitOk;
}

}  // namespace

int run_board_command(std::span<const std::string_view> args, const CliContext& ctx) {
  auto split = scenario_command_args(args, kBoardOptions, ctx, kBoardCommand, print_board_help);
  if (const int* status = std::get_if<int>(&split)) return *status;
  const SplitArgs& a = std::get<SplitArgs>(split);
  std::string serial, shell_path, robot_name;
  std::optional<kernel::Duration> duration;
  std::optional<std::uint64_t> seed;
  kernel::Duration stats_every = 5s;
  bool quiet = false;
  bool lockstep = false;
  std::string playground;
  std::uint16_t playground_port = sim::kPlaygroundFirstPort;
  std::optional<double> speed_scale;
  view::ViewRequest view_request;
  std::optional<std::string> token;
  std::optional<io::DdsFrameOptions> dds;
  io::DdsFrameOptions dds_options;
  std::string dds_option;  // the last DDS option given
  for (const ParsedOption& o : a.options) {
    if (o.name == "--dds") {
      dds = io::DdsFrameOptions{};
      continue;
    }
    auto link_option = parse_dds_option(o, dds_options, dds_option);
    if (auto* e = std::get_if<UsageError>(&link_option)) return usage_error(ctx, kBoardCommand, *e);
    if (std::get<bool>(link_option)) continue;
    if (o.name == "--serial" || o.name == "--shell" || o.name == "--robot") {
      if (o.value.empty()) return usage_error(ctx, kBoardCommand, UsageError{std::string(o.name) + ": empty value"});
      (o.name == "--serial" ? serial : o.name == "--shell" ? shell_path : robot_name) = o.value;
    } else if (o.name == "--duration" || o.name == "--stats-every") {
      auto v = parse_duration(o.name, o.value, std::chrono::hours(24 * 365));
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kBoardCommand, *e);
      if (o.name == "--duration")
        duration = std::get<kernel::Duration>(v);
      else
        stats_every = std::get<kernel::Duration>(v);
    } else if (o.name == "--seed") {
      auto v = parse_u64("--seed", o.value);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kBoardCommand, *e);
      seed = std::get<std::uint64_t>(v);
    } else if (o.name == "--quiet") {
      quiet = true;
    } else if (o.name == "--lockstep") {
      lockstep = true;
    } else if (o.name == "--view") {
      auto v = view::parse_view(o.value);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kBoardCommand, *e);
      view_request = std::get<view::ViewRequest>(v);
    } else if (o.name == "--token") {
      if (o.value.empty()) return usage_error(ctx, kBoardCommand, UsageError{"--token: empty value"});
      token = o.value;
    } else if (o.name == "--playground") {
      if (o.value.empty()) return usage_error(ctx, kBoardCommand, UsageError{"--playground: empty value"});
      playground = o.value;
    } else if (o.name == "--port") {
      auto v = parse_count("--port", o.value, 1, 65535);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kBoardCommand, *e);
      playground_port = static_cast<std::uint16_t>(std::get<std::uint64_t>(v));
    } else if (o.name == "--speed-scale") {
      auto v = parse_fraction("--speed-scale", o.value);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kBoardCommand, *e);
      if (std::get<double>(v) <= 0)
        return usage_error(ctx, kBoardCommand, UsageError{"--speed-scale: must be above 0"});
      speed_scale = std::get<double>(v);
    }
  }
  const bool aseba = robot_name.substr(0, 6) == "aseba:";
  AsebaTarget aseba_target;
  if (aseba) {
    auto t = parse_aseba_target(robot_name);
    if (auto* e = std::get_if<UsageError>(&t)) return usage_error(ctx, kBoardCommand, *e);
    aseba_target = std::get<AsebaTarget>(t);
  }
  if (token && !view_request.on) return usage_error(ctx, kBoardCommand, UsageError{"--token is for --view"});
  if (token) view_request.token = *token;
  if (view_request.on && !playground.empty())
    return usage_error(ctx, kBoardCommand, UsageError{"--view: --playground writes a file and exits"});
  if (dds) {
    if (!serial.empty())
      return usage_error(ctx, kBoardCommand, UsageError{"--dds or --serial: the simulator is on one link"});
    if (aseba || !playground.empty())
      return usage_error(ctx, kBoardCommand, UsageError{"--dds is for a module of a 3D scenario"});
    dds = dds_options;
  } else if (!dds_option.empty()) {
    return usage_error(ctx, kBoardCommand, UsageError{dds_option + " is for --dds"});
  }
  if (lockstep && (aseba || !playground.empty()))
    return usage_error(ctx, kBoardCommand,
                       UsageError{"--lockstep is for a board the simulator drives (--serial, or --dds in 3D)"});
  if (serial.empty() && !dds && !aseba && playground.empty())
    return usage_error(ctx, kBoardCommand, UsageError{"missing --serial PATH (the data line)"});

  auto loaded = sim::load_scenario(std::string(a.positional.front()));
  if (!loaded) {
    ctx.err << kBoardCommand << ": " << loaded.error() << "\n";
    return kExitFailure;
  }
  const sim::Scenario& sc = *loaded;
  if (!playground.empty()) return write_playground(sc, playground, playground_port, ctx);
  if (aseba) {
    BoardAsebaArgs ba;
    ba.target = aseba_target;
    ba.shell = shell_path;
    ba.seed = seed;
    ba.duration = duration;
    ba.stats_every = stats_every;
    ba.speed_scale = speed_scale;
    ba.quiet = quiet;
    ba.view = view_request;
    return run_board_aseba(sc, ba, ctx);
  }
  if (sc.world_kind == sim::WorldKind::kMujoco) {
    BoardOrganismArgs oa;
    oa.view = view_request;
    oa.serial = serial;
    oa.dds = dds;
    oa.shell = shell_path;
    oa.robot = robot_name;
    oa.seed = seed;
    oa.duration = duration;
    oa.stats_every = stats_every;
    oa.quiet = quiet;
    return run_board_organism(sc, oa, ctx);
  }
  std::size_t index = 0;
  if (!robot_name.empty()) {
    while (index < sc.robots.size() && sc.robots[index].name != robot_name) ++index;
    if (index == sc.robots.size()) {
      std::string names;
      for (const auto& r : sc.robots) names += (names.empty() ? "" : ", ") + r.name;
      ctx.err << kBoardCommand << ": --robot: the scenario has no robot " << quote_arg(robot_name) << " (it has "
              << names << ")\n";
      return kExitUsage;
    }
  }
  if (sc.robots.empty()) {
    ctx.err << kBoardCommand << ": " << sc.file << ": the scenario has no robots\n";
    return kExitFailure;
  }
  const sim::RobotSpec& spec = sc.robots[index];

  auto port = std::make_shared<io::SerialPort>("uart0", serial);
  if (auto st = port->open(); !st) {
    ctx.err << kBoardCommand << ": " << st.error() << "\n";
    return kExitFailure;
  }
  (void)port->ioctl("flush");  // frames from before this board started answer nothing
  std::shared_ptr<io::SerialPort> shell_port;
  if (!shell_path.empty()) {
    shell_port = std::make_shared<io::SerialPort>("uart1", shell_path);
    if (auto st = shell_port->open(); !st) {
      ctx.err << kBoardCommand << ": " << st.error() << "\n";
      return kExitFailure;
    }
  }

  if (lockstep) {
    BoardLockstepArgs la;
    la.port = port;
    la.shell_port = shell_port;
    la.serial = serial;
    la.shell_path = shell_path;
    la.seed = seed;
    la.duration = duration;
    la.stats_every = stats_every;
    la.quiet = quiet;
    la.view = view_request;
    return run_board_lockstep(sc, index, la, ctx);
  }
  kernel::ThreadExecutor executor;
  sim::BoardLinkOptions lo;
  lo.control_period = sc.control_period;
  auto link = sim::BoardLink::create(port, lo);
  sim::RobotSystemOptions ro;
  ro.control_period = sc.control_period;
  ro.seed = sim::robot_node_seed(seed.value_or(sc.seed), index);
  ro.read_program = sim::file_program_reader(sc.base_dir);
  ro.make_device_tasks = link->device_tasks();
  auto log_sink = std::make_shared<PrefixedLogSink>(ctx.err, "board " + spec.name + ": ");
  auto built = sim::RobotSystem::build(executor, spec, sim::RobotDevices{}, ro);
  if (!built) {
    ctx.err << kBoardCommand << ": " << built.error() << "\n";
    return kExitFailure;
  }
  std::unique_ptr<sim::RobotSystem> system = std::move(built).value();
  // What happened while building is in the log already; from now on it is printed as it comes.
  if (!quiet) {
    for (const os::LogEntry& e : system->node().log().since(0)) log_sink->write(e);
    system->node().log().add_sink(log_sink);
  }
  if (shell_port) {
    auto devices = std::make_shared<shell::DeviceTable>();
    (*devices)["uart0"] = port;
    (*devices)["uart1"] = shell_port;
    shell::ShellOptions so;
    so.devices = devices;
    auto attached = shell::attach_shell(system->node(), shell_port, so);
    if (!attached) {
      ctx.err << kBoardCommand << ": shell: " << attached.error() << "\n";
      return kExitFailure;
    }
  }
  auto view_started = BoardView::start(view_request, spec.name, system->node(), sc.name, ctx.err);
  if (!view_started) {
    ctx.err << kBoardCommand << ": " << view_started.error() << "\n";
    return kExitFailure;
  }
  BoardView board_view = std::move(view_started).value();
  ctx.out << "board: robot " << spec.name << " of " << sc.name << " on " << serial
          << (shell_port ? ", shell on " + shell_path : std::string()) << "; " << system->node().task_count()
          << " tasks; Ctrl-C to stop\n"
          << std::flush;

  InterruptFlag interrupt;
  const auto start = std::chrono::steady_clock::now();
  auto next_stats = start + stats_every;
  std::string cycle;
  while (!interrupt.raised() && (!duration || std::chrono::steady_clock::now() - start < *duration)) {
    std::this_thread::sleep_for(20ms);
    board_view.between();
    if (cycle = system->node().cycle_error(); !cycle.empty()) break;
    if (std::chrono::steady_clock::now() >= next_stats) {
      next_stats += stats_every;
      ctx.err << "board: " << sim::describe(link->stats()) << "\n" << std::flush;
    }
  }
  system->node().log().remove_sink(log_sink);
  board_view.stop();
  system.reset();  // every task stopped: the link's counters are final
  const sim::BoardLinkStats s = link->stats();
  ctx.out << "board: " << sim::describe(s) << "\n"
          << "board-stats: good=" << s.ir_frames << " bad=" << s.bad_frames() << " missed=" << s.missed
          << " stale=" << s.stale << " out_of_order=" << s.out_of_order << " malformed=" << s.malformed
          << " losses=" << s.link_losses << " recoveries=" << s.link_recoveries << " wheels=" << s.wheel_commands
          << " watchdog=" << s.watchdog_stops << " bytes_in=" << s.bytes_in << " sent=" << s.frames_written
          << " unsent=" << s.frames_unsent << " line_losses=" << s.line_losses << " line_reopens=" << s.line_reopens
          << " line_down_ms=" << std::chrono::duration_cast<std::chrono::milliseconds>(s.line_down).count()
          << " line_open=" << (s.line_open ? 1 : 0) << "\n";
  port->close();
  if (shell_port) shell_port->close();
  if (!cycle.empty()) {
    ctx.err << kBoardCommand << ": " << cycle << "\n";
    return kExitFailure;
  }
  // A dead link is a failed run: the serial line was down when the board stopped.
  if (!s.line_open) {
    ctx.err << kBoardCommand << ": the serial line " << serial << " was down when the board stopped (down "
            << fixed(std::chrono::duration<double>(s.line_down).count(), 1) << " s in all, " << s.line_losses
            << " loss(es), " << s.line_reopens << " reopening(s))\n";
    return kExitFailure;
  }
  return kExitOk;
}

}  // namespace symb::apps::hil
