// `symb sim` and `symb board` on a 3D scenario (world: {kind: mujoco}): hardware in the loop with
// one module of the organism on the board (docs/hil.md, "3D: one module on a board"). The
// simulator runs the organism in process (OrganismSession) with the board's module's node
// replaced by the serial line (HilOrganism); the board runs that module's node over the line's
// devices (HilModuleBoard). With --dds the line is a DDS frame stream instead (io::DdsFrameStream,
// the split world's: topics rt/<prefix>/<module>/to_robot and .../to_world), so the module runs in
// another process of this machine or the network; a board over DDS ends when the simulator's
// stream does. Called by run_sim_command and run_board_command once the scenario is loaded and
// found to be 3D.
#include <chrono>
#include <sstream>

#include "symb/apps/hil/hil_commands.hpp"
#include "symb/apps/hil/hil_common.hpp"
#include "symb/apps/progress_line.hpp"
#include "symb/apps/run/organism_recorder.hpp"
#include "symb/apps/run/remote_robots.hpp"
#include "symb/io/serial_port.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/sim/mujoco/hil_module_board.hpp"
#include "symb/sim/mujoco/hil_organism.hpp"
#include "symb/sim/mujoco/organism_session.hpp"
#include "symb/sim/robot_system.hpp"

namespace symb::apps::hil {

namespace {

using namespace std::chrono_literals;

// The index of module `name`, or a usage error listing the names.
std::variant<std::size_t, std::string> module_index(const sim::Scenario& sc, const std::string& name,
                                                    const char* option) {
  for (std::size_t i = 0; i < sc.robots.size(); ++i)
    if (sc.robots[i].name == name) return i;
  std::string names;
  for (const auto& r : sc.robots) names += (names.empty() ? "" : ", ") + r.name;
  return std::string(option) + ": the scenario has no module " + quote_arg(name) + " (it has " + names + ")";
}

// The module's DDS frame stream as the line the simulator watches (HilOrganism): a peer gone
// (its process killed, or ended) is a line down, whose open() fails until a writer of the peer's
// topic is back, as a serial device's path that is not there; so a dead board is reported once,
// retried with backoff and, still gone at the end, a dead link.
class DdsLine final : public io::IOStream {
 public:
  explicit DdsLine(std::shared_ptr<io::DdsFrameStream> stream)
      : Device(stream->name()), IOStream(stream->name()), s_(std::move(stream)) {}
  kernel::Status open() override {
    if (s_->is_open()) return s_->open();
    return kernel::Error{"the peer on " + s_->read_topic() + " is " + io::to_string(s_->peer())};
  }
  void close() override { s_->close(); }
  bool is_open() const override { return s_->is_open(); }
  kernel::Result<std::size_t> read_some(std::span<std::byte> buf, kernel::Duration timeout) override {
    return s_->read_some(buf, timeout);
  }
  kernel::Status write_all(std::span<const std::byte> data) override { return s_->write_all(data); }

 private:
  std::shared_ptr<io::DdsFrameStream> s_;
};

// The module's DDS frame stream: the simulator writes to_robot and reads to_world, the board the
// other way round.
struct DdsLink {
  std::shared_ptr<io::DdsFrameLinks> links;
  std::shared_ptr<io::DdsFrameStream> stream;
  std::string what;  // "DDS rt/symb/m4/to_world (domain 0)": where it listens
};

kernel::Result<DdsLink> open_dds_link(const io::DdsFrameOptions& options, const std::string& module, bool simulator) {
  auto links = io::DdsFrameLinks::create(options);
  if (!links) return kernel::Error{"--dds: " + links.error()};
  auto stream = simulator ? (*links)->stream(module, run::kToRobot, run::kToWorld)
                          : (*links)->stream(module, run::kToWorld, run::kToRobot);
  if (!stream) return kernel::Error{"--dds: " + stream.error()};
  DdsLink l{*links, *stream, {}};
  l.what = "DDS " + l.stream->read_topic() + " (domain " + std::to_string(options.domain) + ")";
  return l;
}

}  // namespace

int run_sim_organism(const sim::Scenario& sc, const SimOrganismArgs& args, const CliContext& ctx) {
  constexpr std::string_view kCommand = "symb sim";
  if (args.serial.size() != (args.dds ? 0u : 1u)) {
    ctx.err << kCommand << ": a 3D scenario runs one module on a board: give one --serial path (or --dds)\n";
    return kExitUsage;
  }
  if (args.board.empty()) {
    ctx.err << kCommand << ": a 3D scenario needs --board NAME, the module that runs on the board\n";
    return kExitUsage;
  }
  auto index = module_index(sc, args.board, "--board");
  if (auto* e = std::get_if<std::string>(&index)) {
    ctx.err << kCommand << ": " << *e << "\n";
    return kExitUsage;
  }
  const std::size_t module = std::get<std::size_t>(index);
  if (auto st = sim::mujoco::HilOrganism::check(sc, module); !st) {
    ctx.err << kCommand << ": " << st.error() << "\n";
    return kExitFailure;
  }
  const std::uint64_t seed = args.seed.value_or(sc.seed);
  kernel::VirtualTimeExecutor ex;
  sim::SessionOptions so;
  so.seed = seed;
  auto made = sim::mujoco::OrganismSession::create(sc, ex, so);
  if (!made) {
    ctx.err << kCommand << ": " << made.error() << "\n";
    return kExitFailure;
  }
  sim::mujoco::OrganismSession& session = **made;
  std::shared_ptr<io::IOStream> port;
  std::optional<DdsLink> dds;
  std::string where;
  if (args.dds) {
    auto l = open_dds_link(*args.dds, args.board, true);
    if (!l) {
      ctx.err << kCommand << ": " << l.error() << "\n";
      return kExitFailure;
    }
    dds = std::move(l).value();
    port = std::make_shared<DdsLine>(dds->stream);
    where = dds->what;
  } else {
    auto serial = std::make_shared<io::SerialPort>("data." + args.board, args.serial.front());
    if (auto st = serial->open(); !st) {
      ctx.err << kCommand << ": " << st.error() << "\n";
      return kExitFailure;
    }
    (void)serial->ioctl("flush");
    port = serial;
    where = args.serial.front();
  }
  sim::mujoco::HilOrganismOptions ho;
  ho.paced = !args.lockstep;
  ho.answer_wait = args.lockstep ? std::chrono::duration_cast<kernel::Duration>(1s) : sc.control_period;
  ho.hold = args.hold;
  ho.corrupt = args.corrupt;
  ho.seed = seed;
  ho.on_event = [&ctx](const std::string& text) { ctx.err << "sim: " << text << "\n" << std::flush; };
  auto hil = sim::mujoco::HilOrganism::create(session, ex, module, port, ho);
  if (!hil) {
    ctx.err << kCommand << ": " << hil.error() << "\n";
    return kExitFailure;
  }
  run::OrganismRecorderOptions ro;
  ro.caption = sc.name + " (module " + args.board + " on the board), seed " + std::to_string(seed);
  run::OrganismRecorder recorder(session.runner(), ro);

  ctx.err << "sim: " << sc.name << ", seed " << seed << ": waiting for the board (" << args.board << ") on " << where
          << "\n"
          << std::flush;
  if (auto st = (*hil)->wait_for_board(args.wait); !st) {
    ctx.err << kCommand << ": " << st.error() << "\n";
    return kExitFailure;
  }
  const std::uint64_t ticks = static_cast<std::uint64_t>(args.duration / sc.control_period);
  InterruptFlag interrupt;
  ProgressLine progress(ctx.err, !args.quiet, ctx.err_is_terminal);
  const auto wall_start = std::chrono::steady_clock::now();
  std::uint64_t done = 0;
  while (done < ticks && !interrupt.raised()) {
    const std::uint64_t slice = std::min<std::uint64_t>(33, ticks - done);
    auto ran = (*hil)->run_ticks(slice);
    if (!ran) {
      ctx.err << kCommand << ": " << ran.error() << "\n";
      return kExitFailure;
    }
    done += *ran;
    progress.update(static_cast<double>(done) / static_cast<double>(std::max<std::uint64_t>(ticks, 1)),
                    "sim: tick " + std::to_string(done) + " / " + std::to_string(ticks));
  }
  if (dds) {
    // Everything sent reaches the board, then it sees this end leave, not get lost: its run ended.
    (void)dds->stream->flush(std::chrono::seconds(2));
    dds->stream->finish_sending();
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  const double simulated = std::chrono::duration<double>(sc.control_period).count() * static_cast<double>(done);
  progress.finish("sim: " + fixed(simulated, 1) + " s simulated in " + fixed(wall, 1) + " s");
  const auto st = (*hil)->stats();
  std::ostringstream header;
  header << "scenario: " << sc.name << " (" << sc.file << ")\n"
         << "world: MuJoCo (3D), " << sc.robots.size() << " modules, " << args.board << " on the board\n"
         << "seed: " << seed << "\n"
         << "executor: hardware-in-the-loop, " << (args.lockstep ? "lockstep" : "wall clock") << "\n"
         << "transport: " << (dds ? "" : "serial line ") << where << "\n"
         << "control period: " << fixed(std::chrono::duration<double>(sc.control_period).count() * 1000, 1) << " ms\n"
         << "simulated: " << fixed(simulated, 2) << " s\n"
         << "wall clock: " << fixed(wall, 3) << " s\n"
         << "trajectory hash: " << hex64(recorder.summary().hash) << "\n"
         << "corrupt: " << args.corrupt << "\n"
         << "link: " << sim::mujoco::describe(st) << "\n"
         << "link-stats: sent=" << st.frames_sent << " corrupted=" << st.corrupted << " received=" << st.received
         << " bad=" << st.bad_frames() << " applied=" << st.applied << " late=" << st.late << " stale=" << st.stale
         << " superseded=" << st.superseded << " missing=" << st.missing << " silences=" << st.silences
         << " docking=" << st.dock_commands << " docking_refused=" << st.dock_refused << " unsent=" << st.unsent
         << " line_losses=" << st.line_losses << " line_reopens=" << st.line_reopens
         << " line_down_ms=" << kernel::to_milliseconds(st.line_down) << " line_open=" << (st.line_open ? 1 : 0)
         << "\n";
  const std::string dead = st.line_open ? std::string()
                                        : args.board + " (down " +
                                              fixed(std::chrono::duration<double>(st.line_down).count(), 1) +
                                              " s in all, " + std::to_string(st.line_losses) + " loss(es))";
  const std::string line = dds ? "the DDS link" : "the serial line";
  if (!dead.empty()) header << "dead link: " << line << " was down at the end of the run: " << dead << "\n";
  const std::filesystem::path dir = args.out_dir.value_or(std::filesystem::path("out") / (sc.name + "-hil"));
  auto files = recorder.finish(dir, header.str());
  if (!files) {
    ctx.err << kCommand << ": " << files.error() << "\n";
    return kExitFailure;
  }
  ctx.out << "sim: " << sc.name << ", seed " << seed << ", " << fixed(simulated, 1) << " s, module " << args.board
          << " on the board\n"
          << "  link " << args.board << ": " << sim::mujoco::describe(st) << "\n"
          << "  trajectory hash: " << hex64(recorder.summary().hash) << "\n"
          << "results in " << dir.string() << "/\n";
  if (!dead.empty()) {
    ctx.err << kCommand << ": dead link: " << line << " was down at the end of the run: " << dead << "\n";
    return kExitFailure;
  }
  return kExitOk;
}

int run_board_organism(const sim::Scenario& sc, const BoardOrganismArgs& args, const CliContext& ctx) {
  constexpr std::string_view kCommand = "symb board";
  if (args.robot.empty()) {
    ctx.err << kCommand << ": a 3D scenario needs --robot NAME, the module this board runs\n";
    return kExitUsage;
  }
  auto index = module_index(sc, args.robot, "--robot");
  if (auto* e = std::get_if<std::string>(&index)) {
    ctx.err << kCommand << ": " << *e << "\n";
    return kExitUsage;
  }
  const std::size_t module = std::get<std::size_t>(index);
  const sim::RobotSpec& spec = sc.robots[module];
  std::shared_ptr<io::IOStream> port;
  std::optional<DdsLink> dds;
  std::string where = args.serial;
  if (args.dds) {
    auto l = open_dds_link(*args.dds, spec.name, false);
    if (!l) {
      ctx.err << kCommand << ": " << l.error() << "\n";
      return kExitFailure;
    }
    dds = std::move(l).value();
    port = dds->stream;
    where = dds->what;
  } else {
    port = std::make_shared<io::SerialPort>("uart0", args.serial);
    if (auto st = port->open(); !st) {
      ctx.err << kCommand << ": " << st.error() << "\n";
      return kExitFailure;
    }
    (void)port->ioctl("flush");
  }
  std::shared_ptr<io::SerialPort> shell_port;
  if (!args.shell.empty()) {
    shell_port = std::make_shared<io::SerialPort>("uart1", args.shell);
    if (auto st = shell_port->open(); !st) {
      ctx.err << kCommand << ": " << st.error() << "\n";
      return kExitFailure;
    }
  }
  kernel::VirtualTimeExecutor ex;
  sim::mujoco::HilModuleBoardOptions bo;
  bo.control_period = sc.control_period;
  bo.on_event = [&ctx, &spec](const std::string& text) {
    ctx.err << "board " << spec.name << ": " << text << "\n" << std::flush;
  };
  sim::mujoco::HilModuleBoard board(ex, spec.module_kind, port, bo);
  sim::RobotSystemOptions ro;
  ro.control_period = sc.control_period;
  ro.seed = sim::robot_node_seed(args.seed.value_or(sc.seed), module);
  ro.read_program = sim::file_program_reader(sc.base_dir);
  sim::RobotDevices devices;
  devices.module = board.device_lookups();
  auto built = sim::RobotSystem::build(ex, spec, std::move(devices), ro);
  if (!built) {
    ctx.err << kCommand << ": " << built.error() << "\n";
    return kExitFailure;
  }
  std::unique_ptr<sim::RobotSystem> system = std::move(built).value();
  std::string ended;
  bool lost = false;
  FrameBoardRun run;
  run.board = &board;
  run.executor = &ex;
  run.node = &system->node();
  run.devices = board.devices();
  run.what = "module";
  run.robot = spec.name;
  run.scenario = sc.name;
  run.where = where;
  run.data = port;
  run.reopen = !dds;
  run.gone = [&](const std::string& error) {
    // Not the simulator (a foreign writer that came and went): wait on for it.
    if (board.stats().handshakes == 0) return true;
    // Over DDS the simulator's stream ends with its run (it left) or with its process (lost).
    lost = dds->stream->peer() != io::DdsPeerState::kLeft;
    ended = lost ? "the simulator is gone without ending the run (" + error + ")" : "the simulator ended its run";
    ctx.err << "board " << spec.name << ": " << ended << "\n" << std::flush;
    return false;
  };
  run.shell_port = shell_port;
  run.shell_path = args.shell;
  run.quiet = args.quiet;
  run.view = args.view;
  run.stats = [&board] { return sim::mujoco::describe(board.stats()); };
  run.duration = args.duration;
  run.stats_every = args.stats_every;
  auto ran = run_frame_board(run, ctx);
  if (!ran) {
    ctx.err << kCommand << ": " << ran.error() << "\n";
    return kExitFailure;
  }
  const FrameBoardEnd& end = *ran;
  const auto s = board.stats();
  ctx.out << "board: " << sim::mujoco::describe(s) << "\n"
          << frame_board_stats_line(s, end, " docking=" + std::to_string(s.dock_commands)) << "\n";
  system.reset();
  port->close();
  if (shell_port) shell_port->close();
  // A message cycle first, then a simulator gone from DDS, then a dead serial line.
  const std::string failure = end.cycle.empty() && lost ? ended : frame_board_failure(end, args.serial);
  if (!failure.empty()) {
    ctx.err << kCommand << ": " << failure << "\n";
    return kExitFailure;
  }
  return kExitOk;
}

}  // namespace symb::apps::hil
