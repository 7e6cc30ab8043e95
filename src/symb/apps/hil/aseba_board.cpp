// `symb board SCENARIO --robot aseba:tcp:HOST:PORT` (or aseba:serial:PATH): the scenario's robot
// task graph against a Thymio II over the Aseba protocol (a real one on USB, or Aseba
// Playground's on TCP), and `symb board SCENARIO --playground OUT.playground`, which writes the
// scenario's world for Playground. The devices are robot::thymio::AsebaThymio's; the device tasks,
// controllers and shell are a board's (docs/thymio.md).
#include <fstream>
#include <thread>

#include "symb/apps/hil/hil_commands.hpp"
#include "symb/apps/hil/hil_common.hpp"
#include "symb/io/serial_port.hpp"
#include "symb/io/tcp_stream.hpp"
#include "symb/kernel/thread_executor.hpp"
#include "symb/robot/thymio_aseba.hpp"
#include "symb/shell/shell_task.hpp"
#include "symb/sim/playground_world.hpp"
#include "symb/sim/robot_system.hpp"

namespace symb::apps::hil {

namespace {

using namespace std::chrono_literals;

constexpr std::string_view kAsebaBoardCommand = "symb board";

std::string describe(const robot::thymio::AsebaThymioStats& s) {
  return "aseba: node " + std::to_string(s.node) + " '" + s.node_name + "' " + (s.up ? "up" : "DOWN") + "; " +
         std::to_string(s.samples) + " IR samples, " + std::to_string(s.missed_reads) + " reads unanswered; " +
         std::to_string(s.wheel_writes) + " wheel commands, " + std::to_string(s.wheel_refused) + " refused; " +
         std::to_string(s.losses) + " losses, " + std::to_string(s.reconnects) + " reconnects, " +
         std::to_string(s.stops) + " stops; odometry " + fixed(s.path, 1) + " cm; link " + io::aseba::describe(s.link);
}

}  // namespace

std::variant<AsebaTarget, UsageError> parse_aseba_target(std::string_view text) {
  constexpr std::string_view tcp = "aseba:tcp:", serial = "aseba:serial:";
  AsebaTarget t;
  if (text.substr(0, serial.size()) == serial) {
    t.serial_path = std::string(text.substr(serial.size()));
    if (t.serial_path.empty()) return UsageError{"--robot aseba:serial:PATH: no path"};
    return t;
  }
  if (text.substr(0, tcp.size()) != tcp)
    return UsageError{"--robot " + quote_arg(text) + ": an Aseba robot is aseba:tcp:HOST:PORT or aseba:serial:PATH"};
  const std::string_view rest = text.substr(tcp.size());
  const auto colon = rest.rfind(':');
  if (colon == std::string_view::npos || colon == 0)
    return UsageError{"--robot " + quote_arg(text) + ": expected aseba:tcp:HOST:PORT"};
  auto port = parse_count("--robot's port", rest.substr(colon + 1), 1, 65535);
  if (auto* e = std::get_if<UsageError>(&port)) return *e;
  std::string_view host = rest.substr(0, colon);
  if (host.size() > 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  t.host = std::string(host);
  t.port = static_cast<std::uint16_t>(std::get<std::uint64_t>(port));
  return t;
}

int write_playground(const sim::Scenario& sc, const std::string& out, std::uint16_t port, const CliContext& ctx) {
  auto text = sim::playground_world(sc, port);
  if (!text) {
    ctx.err << kAsebaBoardCommand << ": --playground: " << text.error() << "\n";
    return kExitFailure;
  }
  std::ofstream f(out, std::ios::binary | std::ios::trunc);
  f << *text;
  f.close();
  if (!f) {
    ctx.err << kAsebaBoardCommand << ": --playground: cannot write '" << out << "'\n";
    return kExitFailure;
  }
  ctx.out << "playground: wrote " << out << " (" << sc.world.walls.size() << " walls, " << sc.robots.size()
          << " robot(s) from port " << port << "); run it with: QT_QPA_PLATFORM=offscreen asebaplayground " << out
          << "\n";
  return kExitOk;
}

int run_board_aseba(const sim::Scenario& sc, const BoardAsebaArgs& a, const CliContext& ctx) {
  if (sc.world_kind != sim::WorldKind::kEnki || sc.robots.empty()) {
    ctx.err << kAsebaBoardCommand << ": " << sc.file
            << ": an Aseba robot runs a 2D scenario's first robot, and it has none\n";
    return kExitFailure;
  }
  const sim::RobotSpec& spec = sc.robots.front();
  std::shared_ptr<io::IOStream> stream;
  std::string where;
  double speed_scale = a.speed_scale.value_or(1.0);
  if (!a.target.serial_path.empty()) {
    where = a.target.serial_path;
    // A Thymio on USB is a real one: its 500 is 20 cm/s, the simulation's 16.6.
    if (!a.speed_scale)
      speed_scale = robot::thymio::kPlaygroundCmPerSecondPerUnit / robot::thymio::kRealCmPerSecondPerUnit;
    auto port = std::make_shared<io::SerialPort>("thymio", a.target.serial_path);
    if (auto st = port->open(); !st) {
      ctx.err << kAsebaBoardCommand << ": " << st.error() << "\n";
      return kExitFailure;
    }
    stream = port;
  } else {
    where = a.target.host + ":" + std::to_string(a.target.port);
    auto s = io::TcpStream::connect(a.target.host, a.target.port, 2s);
    if (!s) {
      ctx.err << kAsebaBoardCommand << ": " << s.error() << "\n";
      return kExitFailure;
    }
    stream = std::shared_ptr<io::IOStream>(std::move(s).value());
  }
  robot::thymio::AsebaThymioOptions o;
  o.control_period = sc.control_period;
  o.reply_timeout = sc.control_period;
  o.speed_scale = speed_scale;
  if (!a.target.serial_path.empty()) o.cm_per_unit = robot::thymio::kRealCmPerSecondPerUnit;
  auto thymio = robot::thymio::AsebaThymio::create(stream, o);
  if (auto st = thymio->connect(); !st) {
    ctx.err << kAsebaBoardCommand << ": " << where << ": " << st.error() << "\n";
    return kExitFailure;
  }

  kernel::ThreadExecutor executor;
  sim::RobotSystemOptions ro;
  ro.control_period = sc.control_period;
  ro.seed = sim::robot_node_seed(a.seed.value_or(sc.seed), 0);
  ro.read_program = sim::file_program_reader(sc.base_dir);
  sim::RobotDevices devices;
  devices.ir = thymio->ir();
  devices.wheels = thymio->wheels();
  devices.ground = thymio->ground();
  auto built = sim::RobotSystem::build(executor, spec, devices, ro);
  if (!built) {
    ctx.err << kAsebaBoardCommand << ": " << built.error() << "\n";
    return kExitFailure;
  }
  std::unique_ptr<sim::RobotSystem> system = std::move(built).value();
  os::SysLog& log = system->node().log();
  thymio->on_report([&log](os::LogLevel level, std::string_view text) { log.write(level, "aseba", text); });
  auto log_sink = std::make_shared<PrefixedLogSink>(ctx.err, "board " + spec.name + ": ");
  if (!a.quiet) {
    for (const os::LogEntry& e : log.since(0)) log_sink->write(e);
    log.add_sink(log_sink);
  }
  std::shared_ptr<io::SerialPort> shell_port;
  if (!a.shell.empty()) {
    shell_port = std::make_shared<io::SerialPort>("uart1", a.shell);
    if (auto st = shell_port->open(); !st) {
      ctx.err << kAsebaBoardCommand << ": " << st.error() << "\n";
      return kExitFailure;
    }
    auto table = std::make_shared<shell::DeviceTable>();
    (*table)["thymio"] = stream;
    (*table)["uart1"] = shell_port;
    shell::ShellOptions so;
    so.devices = table;
    if (auto attached = shell::attach_shell(system->node(), shell_port, so); !attached) {
      ctx.err << kAsebaBoardCommand << ": shell: " << attached.error() << "\n";
      return kExitFailure;
    }
  }
  auto view_started = BoardView::start(a.view, spec.name, system->node(), sc.name, ctx.err);
  if (!view_started) {
    ctx.err << kAsebaBoardCommand << ": " << view_started.error() << "\n";
    return kExitFailure;
  }
  BoardView board_view = std::move(view_started).value();
  const robot::thymio::AsebaThymioStats first = thymio->stats();
  ctx.out << "board: robot " << spec.name << " of " << sc.name << " on Aseba node " << first.node << " '"
          << first.node_name << "' at " << where << (shell_port ? ", shell on " + a.shell : std::string()) << "; "
          << system->node().task_count() << " tasks; Ctrl-C to stop\n"
          << std::flush;
  thymio->start();

  InterruptFlag interrupt;
  const auto start = std::chrono::steady_clock::now();
  auto next_stats = start + a.stats_every;
  std::string cycle;
  while (!interrupt.raised() && (!a.duration || std::chrono::steady_clock::now() - start < *a.duration)) {
    std::this_thread::sleep_for(20ms);
    board_view.between();
    if (cycle = system->node().cycle_error(); !cycle.empty()) break;
    if (std::chrono::steady_clock::now() >= next_stats) {
      next_stats += a.stats_every;
      ctx.err << "board: " << describe(thymio->stats()) << "\n" << std::flush;
    }
  }
  log.remove_sink(log_sink);
  board_view.stop();
  // First the Thymio's thread (it reports into the node's log) and its wheels (refused from now
  // on, zero targets written when the robot can be reached), then the node.
  thymio->stop();
  system.reset();
  const robot::thymio::AsebaThymioStats s = thymio->stats();
  ctx.out << "board: " << describe(s) << "\n"
          << "aseba-stats: samples=" << s.samples << " missed=" << s.missed_reads << " wheels=" << s.wheel_writes
          << " refused=" << s.wheel_refused << " losses=" << s.losses << " reconnects=" << s.reconnects
          << " stops=" << s.stops << " refused_messages=" << s.link.refused() << " path_cm=" << fixed(s.path, 1)
          << " up=" << (s.up ? 1 : 0) << "\n";
  stream->close();
  if (shell_port) shell_port->close();
  if (!cycle.empty()) {
    ctx.err << kAsebaBoardCommand << ": " << cycle << "\n";
    return kExitFailure;
  }
  if (!s.up) {
    ctx.err << kAsebaBoardCommand << ": the Aseba link to " << where << " was down when the board stopped (" << s.losses
            << " loss(es), " << s.reconnects << " reconnect(s))\n";
    return kExitFailure;
  }
  return kExitOk;
}

}  // namespace symb::apps::hil
