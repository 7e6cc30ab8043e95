// `symb sim SCENARIO --serial PATH`: the simulator side of hardware-in-the-loop. The scenario's
// world runs here at wall-clock pace (or in lockstep with the boards' answers); each robot's
// control system runs on a board (`symb board`) at the other end of its serial line.
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "symb/apps/hil/hil_commands.hpp"
#include "symb/apps/hil/hil_common.hpp"
#include "symb/apps/progress_line.hpp"
#include "symb/apps/run/maze_svg.hpp"
#include "symb/apps/run/run_recorder.hpp"
#include "symb/apps/text_file.hpp"
#include "symb/io/serial_port.hpp"
#include "symb/sim/hil_simulator.hpp"
#include "symb/sim/scenario.hpp"
#include "symb/sim/world_factory.hpp"

namespace symb::apps::hil {

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

constexpr std::string_view kSimCommand = "symb sim";
constexpr kernel::Duration kMaxDuration = sim::kMaxRunDuration;  // a scenario's limit too

constexpr OptionSpec kSimOptions[] = {
    {"--serial", "PATH", "the board's data line; one per robot, comma-separated, in scenario order"},
    {"--duration", "D", "simulated time, also wall clock unless --lockstep (default: the scenario's)"},
    {"--out", "DIR", "output folder (default out/<scenario name>-hil)"},
    {"--seed", "S", "seed of the world, unsigned 64-bit (default: the scenario's)"},
    {"--corrupt", "P", "corrupt this fraction of the IR frames sent (0..1, default 0)"},
    {"--hold", "D", "a silent board's robot keeps its speeds this long, then stops (default 300ms)"},
    {"--wait", "D", "how long to wait for the boards' first answer (default 60s)"},
    {"--board", "NAME", "3D scenarios: the module that runs on the board (the others run here)"},
    {"--lockstep", "", "wait for every answer (up to 1 s) instead of keeping the wall-clock pace"},
    {"--dds", "", "3D scenarios: reach the board over DDS (symb board --dds) instead of --serial"},
    {"--domain", "N", "--dds: the DDS domain id, 0..232 (default 0)"},
    {"--prefix", "NAME", "--dds: the first name of every topic, rt/NAME/... (default symb)"},
    {"--lease", "D", "--dds: a board process silent this long is lost (default 1s)"},
    {"--quiet", "", "no progress line"},
    {"--help", "", "this help"},
};

void print_sim_help(std::ostream& out) {
  out << "Usage: " << kSimCommand << " SCENARIO --serial PATH [options]\n\n"
      << "The simulator side of hardware-in-the-loop (docs/hil.md): runs the scenario's world at\n"
      << "wall-clock pace; after every step (the control period, 30 ms) it sends each robot's 7 IR\n"
      << "values to its board over the serial line and, before the next step, reads the board's\n"
      << "wheel speeds without waiting for them (with --lockstep: waits for them, and keeps no pace;\n"
      << "with a board on the frames too, `symb board --lockstep`, the run is the in-process one).\n"
      << "Start the board first (symb board); `symb link`\n"
      << "makes the serial lines out of pseudo-terminals.\n\n"
      << "Options:\n"
      << describe_options(kSimOptions) << "\n"
      << "Writes trajectory.svg, steps.csv and summary.txt (with the link statistics) into the\n"
      << "output folder. Ctrl-C stops early and still writes them. A line whose device goes away is\n"
      << "reopened with backoff (100 ms doubling to 2 s); the run exits 1 when a line was still down\n"
      << "at its end (a dead link), and summary.txt says how long each line was down.\n";
}

}  // namespace

int run_sim_command(std::span<const std::string_view> args, const CliContext& ctx) {
  auto split = scenario_command_args(args, kSimOptions, ctx, kSimCommand, print_sim_help);
  if (const int* status = std::get_if<int>(&split)) return *status;
  const SplitArgs& a = std::get<SplitArgs>(split);
  std::vector<std::string> serial;
  std::optional<kernel::Duration> duration;
  std::optional<fs::path> out_dir;
  std::optional<std::uint64_t> seed;
  sim::HilSimulatorOptions so;
  kernel::Duration wait = 60s;
  bool quiet = false;
  std::string board;
  bool lockstep = false;
  std::optional<io::DdsFrameOptions> dds;
  io::DdsFrameOptions dds_options;
  std::string dds_option;  // the last DDS option given
  for (const ParsedOption& o : a.options) {
    if (o.name == "--dds") {
      dds = io::DdsFrameOptions{};
      continue;
    }
    auto link_option = parse_dds_option(o, dds_options, dds_option);
    if (auto* e = std::get_if<UsageError>(&link_option)) return usage_error(ctx, kSimCommand, *e);
    if (std::get<bool>(link_option)) continue;
    if (o.name == "--board") {
      if (o.value.empty()) return usage_error(ctx, kSimCommand, UsageError{"--board: empty module name"});
      board = o.value;
    } else if (o.name == "--lockstep") {
      lockstep = true;
    } else if (o.name == "--serial") {
      std::string_view rest = o.value;
      while (true) {
        const auto comma = rest.find(',');
        const std::string_view one = rest.substr(0, comma);
        if (one.empty())
          return usage_error(ctx, kSimCommand, UsageError{"--serial: empty path in " + quote_arg(o.value)});
        serial.emplace_back(one);
        if (comma == std::string_view::npos) break;
        rest = rest.substr(comma + 1);
      }
    } else if (o.name == "--duration" || o.name == "--hold" || o.name == "--wait") {
      auto v = parse_duration(o.name, o.value, kMaxDuration);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kSimCommand, *e);
      const auto d = std::get<kernel::Duration>(v);
      if (o.name == "--duration")
        duration = d;
      else if (o.name == "--hold")
        so.hold = d;
      else
        wait = d;
    } else if (o.name == "--out") {
      if (o.value.empty()) return usage_error(ctx, kSimCommand, UsageError{"--out: empty folder name"});
      out_dir = o.value;
    } else if (o.name == "--seed") {
      auto v = parse_u64("--seed", o.value);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kSimCommand, *e);
      seed = std::get<std::uint64_t>(v);
    } else if (o.name == "--corrupt") {
      auto v = parse_fraction("--corrupt", o.value);
      if (auto* e = std::get_if<UsageError>(&v)) return usage_error(ctx, kSimCommand, *e);
      so.corrupt = std::get<double>(v);
    } else if (o.name == "--quiet") {
      quiet = true;
    }
  }
  if (dds) {
    if (!serial.empty())
      return usage_error(ctx, kSimCommand, UsageError{"--dds or --serial: the board is on one link"});
    dds = dds_options;
  } else if (!dds_option.empty()) {
    return usage_error(ctx, kSimCommand, UsageError{dds_option + " is for --dds"});
  }
  if (serial.empty() && !dds)
    return usage_error(ctx, kSimCommand, UsageError{"missing --serial PATH (the board's data line)"});

  auto loaded = sim::load_scenario(std::string(a.positional.front()));
  if (!loaded) {
    ctx.err << kSimCommand << ": " << loaded.error() << "\n";
    return kExitFailure;
  }
  const sim::Scenario& sc = *loaded;
  if (sc.world_kind == sim::WorldKind::kMujoco) {
    SimOrganismArgs oa;
    oa.serial = serial;
    oa.dds = dds;
    oa.board = board;
    oa.seed = seed;
    oa.duration = duration.value_or(sc.duration);
    oa.hold = so.hold;
    oa.wait = wait;
    oa.corrupt = so.corrupt;
    oa.lockstep = lockstep;
    oa.quiet = quiet;
    oa.out_dir = out_dir;
    return run_sim_organism(sc, oa, ctx);
  }
  if (!board.empty() || dds) {
    ctx.err << kSimCommand << ": --board and --dds are for 3D scenarios; " << sc.file
            << " describes a 2D world (one --serial path per robot; over DDS: symb run --bus dds --remote)\n";
    return kExitUsage;
  }
  if (serial.size() != sc.robots.size()) {
    ctx.err << kSimCommand << ": the scenario has " << sc.robots.size() << " robot(s) but " << serial.size()
            << " --serial path(s) were given (one per robot, in scenario order)\n";
    return kExitUsage;
  }
  const std::uint64_t run_seed = seed.value_or(sc.seed);
  const kernel::Duration run_for = duration.value_or(sc.duration);
  so.period = sc.control_period;
  so.seed = run_seed;
  so.lockstep = lockstep;
  so.answer_wait = 1s;
  so.on_event = [&ctx](const std::string& text) { ctx.err << "sim: " << text << "\n" << std::flush; };

  std::unique_ptr<sim::World> world;
  try {
    world = sim::make_world(sc.world, run_seed, sc.robots.size());
    for (const sim::RobotSpec& r : sc.robots) world->add_robot(r.name, r.kind, r.start);
  } catch (const std::exception& e) {
    ctx.err << kSimCommand << ": " << sc.file << ": " << e.what() << "\n";
    return kExitFailure;
  }
  std::vector<std::shared_ptr<io::IOStream>> ports;
  for (std::size_t i = 0; i < serial.size(); ++i) {
    auto p = std::make_shared<io::SerialPort>("data." + sc.robots[i].name, serial[i]);
    if (auto st = p->open(); !st) {
      ctx.err << kSimCommand << ": " << st.error() << "\n";
      return kExitFailure;
    }
    ports.push_back(std::move(p));
  }

  const fs::path dir = out_dir.value_or(fs::path("out") / (sc.name + "-hil"));
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) {
    ctx.err << kSimCommand << ": cannot create " << dir.string() << ": " << ec.message() << "\n";
    return kExitFailure;
  }
  std::ofstream csv(dir / "steps.csv", std::ios::binary);
  if (!csv) {
    ctx.err << kSimCommand << ": cannot write " << (dir / "steps.csv").string() << "\n";
    return kExitFailure;
  }

  const double dt = std::chrono::duration<double>(sc.control_period).count();
  sim::HilSimulator simulator(*world, ports, so);
  run::RunRecorder recorder(*world, &csv, 1, dt);
  ProgressLine progress(ctx.err, !quiet, ctx.err_is_terminal);
  const double total = std::chrono::duration<double>(run_for).count();
  simulator.add_observer([&](const sim::StepRecord& r) {
    recorder.on_step(r);
    if (r.step % 33 == 0) {
      const double t = static_cast<double>(r.step) * dt;
      progress.update(total > 0 ? t / total : 1.0, "sim: " + fixed(t, 1) + " / " + fixed(total, 1) + " s");
    }
  });

  // Ctrl-C: the stepping thread is told to stop, and the files are still written.
  InterruptFlag interrupt;
  std::atomic<bool> done{false};
  std::thread watcher([&] {
    while (!done.load()) {
      if (interrupt.raised()) simulator.stop();
      std::this_thread::sleep_for(20ms);
    }
  });
  const auto finish_watcher = [&] {
    done = true;
    watcher.join();
  };

  ctx.err << "sim: " << sc.name << ", seed " << run_seed << ": waiting for the board on " << serial.front()
          << (serial.size() > 1 ? " (and " + std::to_string(serial.size() - 1) + " more)" : std::string()) << "\n"
          << std::flush;
  if (auto st = simulator.wait_for_boards(wait); !st) {
    finish_watcher();
    ctx.err << kSimCommand << ": " << st.error() << "\n";
    return kExitFailure;
  }
  const auto wall_start = std::chrono::steady_clock::now();
  auto ran = simulator.run_for(run_for);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  finish_watcher();
  progress.finish("sim: " + fixed(world->time(), 1) + " s simulated in " + fixed(wall, 1) + " s");
  if (!ran) {
    ctx.err << kSimCommand << ": " << ran.error() << "\n";
    return kExitFailure;
  }

  const auto link = simulator.stats();
  std::ostringstream summary;
  summary << "scenario: " << sc.name << " (" << sc.file << ")\n"
          << "seed: " << run_seed << "\n"
          << "executor: hardware-in-the-loop, " << (lockstep ? "lockstep" : "wall clock") << "\n"
          << "control period: " << fixed(dt * 1000, 1) << " ms\n"
          << "simulated: " << fixed(world->time(), 2) << " s in " << recorder.steps() << " steps\n"
          << "wall clock: " << fixed(wall, 3) << " s\n"
          << "overruns: " << simulator.overruns() << "\n"
          << "corrupt: " << so.corrupt << "\n"
          << "trajectory hash: " << hex64(recorder.hash()) << "\n\n"
          << "robot,distance_m,contacts,contact_steps,moving_s,end_x_cm,end_y_cm\n";
  for (const auto& x : recorder.summaries())
    summary << x.name << "," << fixed(x.distance / 100, 3) << "," << x.contact_events << "," << x.contact_steps << ","
            << fixed(x.moving_seconds, 2) << "," << fixed(x.end.x, 1) << "," << fixed(x.end.y, 1) << "\n";
  summary << "\nrobot,frames_sent,corrupted,write_errors,received,bad,applied,late,stale,superseded,missing,silences,"
             "recoveries,unsent,line_losses,line_reopens,line_down_ms,line_open\n";
  std::string dead;  // the robots whose line was down at the end
  for (const auto& s : link) {
    const auto down_ms = std::chrono::duration_cast<std::chrono::milliseconds>(s.line_down).count();
    summary << s.robot << "," << s.frames_sent << "," << s.corrupted << "," << s.write_errors << "," << s.received
            << "," << s.bad_frames() << "," << s.applied << "," << s.late << "," << s.stale << "," << s.superseded
            << "," << s.missing << "," << s.silences << "," << s.recoveries << "," << s.unsent << "," << s.line_losses
            << "," << s.line_reopens << "," << down_ms << "," << (s.line_open ? 1 : 0) << "\n";
    if (!s.line_open)
      dead += (dead.empty() ? "" : "; ") + s.robot + " (down " + fixed(static_cast<double>(down_ms) / 1000, 1) +
              " s in all, " + std::to_string(s.line_losses) + " loss(es))";
  }
  if (!dead.empty()) summary << "\ndead link: the serial line was down at the end of the run: " << dead << "\n";
  csv.close();
  std::ostringstream svg;
  run::write_maze_svg(
      svg, sc.world, recorder.paths(),
      sc.name + " (hardware in the loop), seed " + std::to_string(run_seed) + ", " + fixed(world->time(), 1) + " s");
  for (const auto& [name, text] : {std::pair{"trajectory.svg", svg.str()}, std::pair{"summary.txt", summary.str()}})
    if (auto st = write_file(dir / name, text); !st) {
      ctx.err << kSimCommand << ": " << st.error() << "\n";
      return kExitFailure;
    }
  if (!csv) {
    ctx.err << kSimCommand << ": cannot write " << (dir / "steps.csv").string() << "\n";
    return kExitFailure;
  }

  ctx.out << "sim: " << sc.name << ", seed " << run_seed << ", " << fixed(world->time(), 1)
          << (lockstep ? " s in lockstep with the boards\n" : " s at wall-clock pace\n");
  for (const auto& x : recorder.summaries())
    ctx.out << "  " << x.name << ": " << fixed(x.distance / 100.0, 2) << " m travelled, " << x.contact_events
            << " contacts (" << x.contact_steps << " steps touching), moving " << fixed(x.moving_seconds, 1) << " s\n";
  for (const auto& s : link) ctx.out << "  link " << s.robot << ": " << sim::describe(s) << "\n";
  ctx.out << "results in " << dir.string() << "/\n"
          << "  " << (dir / "trajectory.svg").string() << "\n  " << (dir / "steps.csv").string() << "\n  "
          << (dir / "summary.txt").string() << "\n";
  if (!dead.empty()) {
    ctx.err << kSimCommand << ": dead link: the serial line was down at the end of the run: " << dead << "\n";
    return kExitFailure;
  }
  return kExitOk;
}

}  // namespace symb::apps::hil
