#include "symb/apps/run/scenario_run.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <fstream>
#include <memory>
#include <sstream>
#include <thread>

#include "symb/apps/cli_args.hpp"
#include "symb/apps/run/huge_page_heap.hpp"
#include "symb/apps/run/maze_svg.hpp"
#include "symb/apps/run/organism_run.hpp"
#include "symb/apps/run/probe_plot.hpp"
#include "symb/apps/run/probe_recorder.hpp"
#include "symb/apps/run/run_loop.hpp"
#include "symb/apps/run/run_recorder.hpp"
#include "symb/apps/run/spike_recorder.hpp"
#include "symb/apps/text_file.hpp"
#include "symb/apps/view/live_view.hpp"
#include "symb/io/plugin_library.hpp"
#include "symb/io/stdio_stream.hpp"
#include "symb/kernel/lockstep_executor.hpp"
#include "symb/kernel/thread_executor.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/syslog.hpp"
#include "symb/shell/shell_task.hpp"
#include "symb/shell/tcp_shell.hpp"
#include "symb/sim/mujoco/organism_session.hpp"
#include "symb/sim/scenario_session.hpp"

namespace symb::apps::run {

namespace {

namespace fs = std::filesystem;
using kernel::Error;

constexpr std::size_t kMaxProbePlots = 48;

double seconds(kernel::Duration d) { return std::chrono::duration<double>(d).count(); }

std::string summary_text(const sim::Scenario& sc, const RunResult& r) {
  std::ostringstream s;
  s << "scenario: " << sc.name << " (" << sc.file << ")\n"
    << "seed: " << r.seed << "\n"
    << "executor: "
    << (r.realtime                          ? std::string("threads, wall clock")
        : !r.lockstep && r.organism.empty() ? std::string("virtual time, one executor (a single robot)")
                                            : "virtual time, " + std::to_string(r.threads) + " worker thread(s)")
    << "\n"
    << "control period: " << fixed(seconds(sc.control_period) * 1000, 1) << " ms\n"
    << "simulated: " << fixed(r.simulated_seconds, 2) << " s in " << r.steps << " steps\n";
  if (r.interrupted)
    s << "interrupted: at " << fixed(r.simulated_seconds, 2) << " s of " << fixed(r.planned_seconds, 2)
      << " s (a stop was requested: Ctrl-C or SIGTERM)\n";
  s << "wall clock: " << fixed(r.wall_seconds, 3) << " s\n"
    << "real-time factor: " << fixed(r.real_time_factor, 1) << "\n";
  if (r.lockstep)
    s << "robots' nodes: " << fixed(100 * r.nodes_share, 0) << "% of the wall clock (the part --threads spreads)\n";
  if (!r.heap.empty()) s << r.heap << "\n";
  s << "trajectory hash: " << hex64(r.trajectory_hash) << "\n";
  s << r.remote;
  const RecordFigures& rec = r.recording;
  if (!rec.format.empty())
    s << "recording: " << rec.format << ", " << rec.recorded_steps << " steps x " << rec.recorded_robots << " robots, "
      << fixed(static_cast<double>(rec.bytes) / 1e6, 2) << " MB; " << fixed(rec.step_seconds, 3) << " s in the steps ("
      << fixed(r.steps > 0 ? 1000 * rec.step_seconds / static_cast<double>(r.steps) : 0.0, 3) << " ms per step), "
      << fixed(rec.finish_seconds, 3) << " s at the end\n";
  s << "\n"
    << "robot,distance_m,contacts,contact_steps,moving_s,time_in_maze_s,end_x_cm,end_y_cm\n";
  for (const RobotSummary& x : r.robots)
    s << x.name << "," << fixed(x.distance / 100, 3) << "," << x.contact_events << "," << x.contact_steps << ","
      << fixed(x.moving_seconds, 2) << "," << fixed(r.simulated_seconds, 2) << "," << fixed(x.end.x, 1) << ","
      << fixed(x.end.y, 1) << "\n";
  return s.str();
}

// Probe samples of a lockstep run, put back in one order that does not depend on the threads:
// each robot's sink keeps its samples in a buffer of its own (only its lane's thread, or the
// main lane's between windows, touches it), and flush(), called on the main lane at each world
// step and after the run, hands them on sorted by time, robot index at one instant, then each
// robot's own order.
class OrderedProbes {
 public:
  OrderedProbes(std::size_t robots, os::ProbeSink out) : buffers_(robots), out_(std::move(out)) {}

  os::ProbeSink sink(std::size_t robot) {
    return [this, robot](const os::ProbeSample& s) {
      buffers_[robot].push_back(Sample{s.time, std::string(s.node), std::string(s.task), std::string(s.channel),
                                       std::vector<float>(s.values.begin(), s.values.end())});
    };
  }

  void flush() {
    order_.clear();
    for (std::size_t r = 0; r < buffers_.size(); ++r)
      for (const Sample& s : buffers_[r]) order_.push_back(&s);
    if (order_.empty()) return;
    std::stable_sort(order_.begin(), order_.end(), [](const Sample* a, const Sample* b) { return a->time < b->time; });
    for (const Sample* s : order_) out_(os::ProbeSample{s->time, s->node, s->task, s->channel, s->values});
    for (auto& b : buffers_) b.clear();
  }

 private:
  struct Sample {
    kernel::Time time;
    std::string node, task, channel;
    std::vector<float> values;
  };
  std::vector<std::vector<Sample>> buffers_;
  std::vector<const Sample*> order_;
  os::ProbeSink out_;
};

}  // namespace

unsigned default_threads(std::size_t robots) {
  if (robots < kParallelRobots) return 1;
  return std::clamp(std::thread::hardware_concurrency(), 1u, 64u);
}

kernel::Result<RunResult> run_scenario(const RunOptions& options) {
  auto loaded = sim::load_scenario(options.scenario_path);
  if (!loaded) return Error{loaded.error()};
  sim::Scenario scenario = std::move(loaded).value();
  if (options.duration) scenario.duration = *options.duration;
  if (options.controller_weights) {
    bool found = false;
    for (sim::RobotSpec& r : scenario.robots)
      for (sim::TaskSpec& t : r.tasks) {
        if (t.name != options.genome_controller) continue;
        found = true;
        const auto p =
            std::find_if(t.params.begin(), t.params.end(), [](const auto& a) { return a.name == "weights"; });
        if (p != t.params.end()) {
          p->value = *options.controller_weights;
        } else {
          t.params.push_back({"weights", *options.controller_weights, 1});
          t.param_where.push_back(t.where);
        }
      }
    if (!found)
      return Error{"--genome: no robot of " + options.scenario_path + " has a task named '" +
                   options.genome_controller + "' (name it with --controller)"};
  }

  RunResult result;
  result.scenario = scenario.name;
  result.realtime = options.realtime;
  if (options.out_dir)
    result.out_dir = *options.out_dir;
  else if (options.out_under)
    result.out_dir = *options.out_under / scenario.name;
  const bool write_files = !result.out_dir.empty();
  std::ofstream probes_csv;

  // 2D in virtual time: the lockstep executor, whatever the number of threads (with one it is the
  // virtual-time executor's run; with more, the same run on more cores). 3D organisms keep one
  // virtual-time executor: their modules meet over the organism bus at any instant, not only at
  // world steps, so their nodes cannot run apart between steps.
  const bool is_organism = scenario.world_kind == sim::WorldKind::kMujoco;
  if (options.threads > 1 && (is_organism || options.realtime))
    return Error{std::string("--threads: ") +
                 (is_organism ? "a 3D organism runs on one thread (its modules meet over the organism bus at any "
                                "instant, not only at world steps)"
                              : "threads are for virtual time; --realtime runs every task on its own thread")};
  // One robot of its own (none remote) on one thread: the virtual-time executor itself. The
  // lockstep executor runs robots' nodes apart between world steps; one robot has nothing to run
  // apart, and the windows (a lane executor, a window a step, the readings handed over at its
  // start) were a ninth of the framework's cost of a step (callgrind, the 1-robot maze: 554
  // instructions of 29,100). The run is the same, bit for bit (tests/apps/threads_run_test.cpp):
  // the world runner is above every task's priority, so at a step's instant the world moves and
  // publishes first on either executor, and the robot's events follow in the same order.
  const bool one_robot =
      !is_organism && scenario.robots.size() == 1 && options.threads <= 1 && options.remote.robots.empty();
  std::unique_ptr<kernel::Executor> executor;
  kernel::VirtualTimeExecutor* virtual_time = nullptr;
  kernel::LockstepExecutor* lockstep = nullptr;
  if (options.realtime) {
    executor = std::make_unique<kernel::ThreadExecutor>(kernel::ThreadExecutor::Options{});
  } else if (is_organism || one_robot) {
    auto v = std::make_unique<kernel::VirtualTimeExecutor>();
    virtual_time = v.get();
    executor = std::move(v);
  } else {
    result.threads = options.threads == 0 ? default_threads(scenario.robots.size()) : options.threads;
    auto l = std::make_unique<kernel::LockstepExecutor>(
        kernel::LockstepExecutor::Options{.threads = result.threads,
                                          .quantum = scenario.control_period,
                                          .prefetch = scenario.robots.size() >= kParallelRobots});
    lockstep = l.get();
    result.lockstep = true;
    executor = std::move(l);
  }

  sim::SessionOptions session_options;
  session_options.seed = options.seed;
  for (const std::string& path : options.plugins) {
    auto lib = io::PluginLibrary::open(path);
    if (!lib) return Error{"--plugin: " + lib.error()};
    session_options.task_types.push_back(
        [lib = std::move(lib).value()](os::TaskTypeRegistry& r) { return lib->register_into(r); });
  }
  if (!options.remote.robots.empty() && (is_organism || options.realtime))
    return Error{std::string("--remote: ") +
                 (is_organism ? scenario.file + ": a 3D organism's modules run in one process "
                                                "(one module can run on a board: symb sim --board)"
                              : "remote robots run in lockstep with the world's virtual time, not with --realtime")};
  if (is_organism && (!options.plugins.empty() || !scenario.plugins.empty()))
    return Error{scenario.file + ": plugins are for 2D scenarios (a 3D organism registers only the built-in types)"};
  if (is_organism) {
    auto organism = sim::mujoco::OrganismSession::create(scenario, *executor, session_options);
    if (!organism) return Error{organism.error()};
    if (options.record.format != RecordFormat::kAuto && options.record.format != RecordFormat::kCsv)
      return Error{"--record: a 3D run records CSV (poses.csv, joints.csv), not " +
                   std::string(record_format_name(options.record.format))};
    if (!options.record.robots.empty()) return Error{"--record-robots: a 3D run records every module"};
    return run_organism(**organism, virtual_time, scenario, options, std::move(result));
  }
  auto created = sim::ScenarioSession::create(scenario, *executor, session_options);
  if (!created) return Error{created.error()};
  std::unique_ptr<sim::ScenarioSession> session = std::move(created).value();
  result.seed = session->seed();
  std::unique_ptr<RemoteRobots> remote;  // destroyed before the session, whose runner it observes
  if (!options.remote.robots.empty()) {
    auto attached = RemoteRobots::attach(*session, options.remote, options.on_notice);
    if (!attached) return Error{attached.error()};
    remote = std::move(attached).value();
  }
  if (write_files) {
    std::error_code ec;
    fs::create_directories(result.out_dir, ec);
    if (ec) return Error{"cannot create " + result.out_dir.string() + ": " + ec.message()};
    probes_csv.open(result.out_dir / "probes.csv", std::ios::binary);
    if (!probes_csv) return Error{"cannot write " + (result.out_dir / "probes.csv").string()};
  }

  auto recording = RunRecording::open(session->world(), scenario, result.seed, options.record, options.csv_every,
                                      write_files ? result.out_dir : fs::path{});
  if (!recording) return Error{recording.error()};
  RunRecorder& recorder = (*recording)->recorder();
  session->runner().add_observer([&recorder](const sim::StepRecord& r) { recorder.on_step(r); });
  // Controllers' internal state, only when there is a folder to put it in.
  // Spiking networks' spikes and layouts go to their own recorder (AEDAT, raster, network picture).
  ProbeRecorder probes(write_files ? &probes_csv : nullptr);
  SpikeRecorder spikes;
  // The web view sees every sample too; it is made further down, once the shell is open.
  std::atomic<view::LiveView*> live_view{nullptr};
  const os::ProbeSink view_sink = [&live_view](const os::ProbeSample& s) {
    if (view::LiveView* v = live_view.load(std::memory_order_acquire)) v->on_probe(s);
  };
  const os::ProbeSink sink = [&probes, &spikes, &view_sink](const os::ProbeSample& s) {
    view_sink(s);
    if (SpikeRecorder::takes(s.channel))
      spikes.record(s);
    else
      probes.record(s);
  };
  // Lockstep: the robots probe from several threads at once; their samples are put in order at
  // each step. Threads (--realtime) have no order to keep: straight to the recorders.
  OrderedProbes ordered(session->robot_count(), sink);
  if (write_files) {
    for (std::size_t i = 0; i < session->robot_count(); ++i)
      session->robot(i).node().set_probe_sink(lockstep ? ordered.sink(i) : sink);
    if (lockstep) session->runner().add_observer([&ordered](const sim::StepRecord&) { ordered.flush(); });
  } else if (options.view.on) {
    // Only the view looks: it keeps the latest sample per series, which needs no order (and
    // takes its own lock when the lanes probe at once).
    for (std::size_t i = 0; i < session->robot_count(); ++i) session->robot(i).node().set_probe_sink(view_sink);
  }
  struct ProbeSinkGuard {  // the sinks point at `probes`, which goes before the session
    sim::ScenarioSession& s;
    ~ProbeSinkGuard() {
      for (std::size_t i = 0; i < s.robot_count(); ++i) s.robot(i).node().set_probe_sink({});
    }
  } probe_sink_guard{*session};

  // The shell's tasks live on the robot's node: closed before the session (and its nodes) go.
  std::unique_ptr<shell::TcpShellServer> tcp_shell;
  std::atomic<bool> running{true};  // false once the run itself stops its tasks
  if (options.shell.kind != ShellRequest::Kind::kNone) {
    sim::RobotSystem* robot =
        options.shell.robot.empty() ? &session->robot(0) : session->find_robot(options.shell.robot);
    if (!robot) return Error{"--shell-robot: the scenario has no robot '" + options.shell.robot + "'"};
    // `load PATH`: a plugin's types into this robot's own registry (docs/plugins.md).
    const auto load_plugin = [robot](const std::string& path) -> kernel::Status {
      auto lib = io::PluginLibrary::open(path);
      if (!lib) return Error{lib.error()};
      return (*lib)->register_into(robot->own_types());
    };
    if (options.shell.kind == ShellRequest::Kind::kTcp) {
      shell::TcpShellOptions so;
      so.session.load_plugin = load_plugin;
      so.host = options.shell.host;
      so.port = options.shell.port;
      if (!options.shell.token.empty()) so.token = options.shell.token;
      auto server = shell::TcpShellServer::start(robot->node(), so);
      if (!server) return Error{"shell: " + server.error()};
      tcp_shell = std::move(server).value();
      if (options.on_notice)
        options.on_notice("shell: symb shell --tcp " + tcp_shell->host() + ":" + std::to_string(tcp_shell->port()) +
                          " --token " + tcp_shell->token() + "   (robot " + robot->name() + ")");
    } else {
      // End of input (a script piped in, a closed terminal) ends the session after its last line;
      // the run goes on to its end (docs/shell.md).
      shell::ShellOptions so;
      so.load_plugin = load_plugin;
      so.on_close = [&running, notice = options.on_notice, end = seconds(scenario.duration)] {
        if (running.load() && notice)
          notice("shell: the session ended (end of input or exit); the run goes on to " + fixed(end, 1) + " s");
      };
      auto attached = shell::attach_shell(robot->node(), std::make_shared<io::StdioStream>(), std::move(so));
      if (!attached) return Error{"shell: " + attached.error()};
    }
  }

  // The web view: made last, so that it goes first (its shell sessions live on the robots' nodes).
  std::optional<RunControl> control;
  if (!options.realtime) control.emplace(options.speed, scenario.control_period);
  std::unique_ptr<view::LiveView> live;
  if (options.view.on) {
    auto started = view::LiveView::start(*session, scenario.name, seconds(scenario.duration),
                                         control ? &*control : nullptr, view::live_view_options(options.view));
    if (!started) return Error{started.error()};
    live = std::move(started).value();
    live_view.store(live.get(), std::memory_order_release);
    if (options.on_notice) options.on_notice("view: " + live->url());
  }

  if (remote)
    if (auto st = remote->wait_for_robots(options.stop_requested); !st) return Error{st.error()};
  // Built: a big swarm's heap goes onto huge pages before the first step (not timed as stepping).
  if (lockstep != nullptr && session->robot_count() >= kParallelRobots) result.heap = back_heap_with_huge_pages().note;
  const auto wall_start = std::chrono::steady_clock::now();
  const auto wall_seconds = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  };
  result.planned_seconds = seconds(scenario.duration);
  session->start();
  const bool stopped = run_slices(
      {.virtual_time = virtual_time,
       .lockstep = lockstep,
       .duration = scenario.duration,
       .speed = options.speed,
       .wall_start = wall_start,
       .on_progress = options.on_progress,
       .stop_requested = options.stop_requested,
       .failed = [&session] { return !session->cycle_error().empty(); },
       .control = live && control ? &*control : nullptr,
       .between_slices = live ? std::function<void()>([&live] { live->between_slices(); }) : std::function<void()>()});
  if (live) live->finish();
  running = false;
  session->stop();
  if (remote) {
    remote->finish(recorder.steps());
    result.remote = remote->summary();
    result.remote_gone = remote->gone();
  }
  ordered.flush();
  result.wall_seconds = wall_seconds();
  live_view.store(nullptr, std::memory_order_release);
  if (live) {
    const view::ViewServerStats vs = live->server().stats();
    result.view_frames = vs.frames.pushed;
    result.view_frames_sent = vs.frames.sent;
    result.view_frames_dropped = vs.frames.dropped;
  }
  live.reset();
  tcp_shell.reset();

  result.interrupted = stopped;
  if (lockstep && lockstep->stats().run_wall.count() > 0)
    result.nodes_share = static_cast<double>(lockstep->stats().lanes_wall.count()) /
                         static_cast<double>(lockstep->stats().run_wall.count());
  result.steps = recorder.steps();
  result.simulated_seconds = session->world().time();
  result.real_time_factor = result.wall_seconds > 0 ? result.simulated_seconds / result.wall_seconds : 0;
  result.trajectory_hash = recorder.hash();
  result.robots = recorder.summaries();

  if (write_files) {
    probes_csv.close();
    if (!probes_csv) return Error{"cannot write " + (result.out_dir / "probes.csv").string()};
    auto recorded = (*recording)
                        ->finish(scenario.world,
                                 scenario.name + ", seed " + std::to_string(result.seed) + ", " +
                                     fixed(result.simulated_seconds, 1) + " s simulated",
                                 result.simulated_seconds, result.interrupted);
    if (!recorded) return Error{recorded.error()};
    result.recording = (*recording)->figures();
    std::ostringstream logs;
    for (std::size_t i = 0; i < session->robot_count(); ++i) {
      os::Node& node = session->robot(i).node();
      for (const os::LogEntry& e : node.log().since(0)) logs << node.name() << " " << os::format_log_entry(e) << "\n";
    }
    const std::pair<const char*, std::string> files[] = {{"summary.txt", summary_text(scenario, result)},
                                                         {"syslog.txt", logs.str()}};
    for (const auto& [name, text] : files)
      if (auto st = write_file(result.out_dir / name, text); !st) return Error{st.error()};
    result.files = std::move(recorded).value();
    result.files.insert(result.files.end(),
                        {result.out_dir / "summary.txt", result.out_dir / "syslog.txt", result.out_dir / "probes.csv"});
    auto spike_files = spikes.write(result.out_dir);
    if (!spike_files) return Error{spike_files.error()};
    result.files.insert(result.files.end(), spike_files->begin(), spike_files->end());
    auto charts = write_probe_charts(result.out_dir / "probes", probes, kMaxProbePlots);
    if (!charts) return Error{charts.error()};
    result.files.insert(result.files.end(), charts->begin(), charts->end());
  }
  if (auto e = session->cycle_error(); !e.empty())
    return Error{e + (write_files ? "; the run so far is in " + result.out_dir.string() : std::string())};
  return result;
}

}  // namespace symb::apps::run
