// Running a 3D organism scenario in-process (`symb run` on a scenario whose world is MuJoCo's):
// the session (one node per module on a MujocoRunner) runs in slices as a 2D one does
// (run_loop.hpp: progress, --speed pacing, Ctrl-C between slices), an OrganismRecorder watches
// the world, and afterwards the output folder gets the recorder's files (organism_recorder.hpp),
// probes.csv and probes/*.svg as in 2D, modules/*.svg (hormone levels side by side per module:
// the gradient along the organism) and syslog.txt.
//
// With --view the run is shown in a browser as a 2D one is (apps/view/organism_view.hpp: the
// modules in 3D, their docking, each module's task graph, probes, SysLog and shell), paced and
// paused from the page; the view only reads, so the run is the one without it.
//
// Session is any type with the organism session's API: start(), stop(), seed(), cycle_error()
// (empty: none), robot_count(), robot(i).node() (an os::Node&), and runner() (the
// sim::mujoco::MujocoRunner&). A template so that apps does not depend on how a session is built.
//
//   auto created = sim::mujoco::OrganismSession::create(scenario, *executor, session_options);
//   if (!created) return Error{created.error()};
//   return run_organism(**created, virtual_time, scenario, options, std::move(result));
#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "symb/apps/run/organism_recorder.hpp"
#include "symb/apps/run/probe_recorder.hpp"
#include "symb/apps/run/run_loop.hpp"
#include "symb/apps/run/scenario_run.hpp"
#include "symb/apps/view/live_view.hpp"
#include "symb/apps/view/organism_view.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/sim/scenario.hpp"

namespace symb::apps::run {

// The recorder's options for this run: --csv-every, and the scenario and seed as the caption.
OrganismRecorderOptions organism_recorder_options(const sim::Scenario& scenario, const RunOptions& options,
                                                  std::uint64_t seed);
// Fills the run's figures from what the recorder saw: steps (control ticks), simulated seconds,
// real-time factor, a summary per module (as RobotSummary: distance in cm, end pose) and the
// trajectory hash.
void fill_organism_result(const OrganismRecorder& recorder, RunResult& result);
// Writes everything into result.out_dir (the recorder's files, the probe charts, syslog.txt from
// `nodes`) and lists the files in result.files.
kernel::Status write_organism_files(OrganismRecorder& recorder, const ProbeRecorder& probes,
                                    const std::vector<os::Node*>& nodes, const sim::Scenario& scenario,
                                    RunResult& result);

// `result` comes with its scenario name, out_dir (empty: no files) and realtime flag set;
// `virtual_time` is the executor the session runs on, or null for threads. A shell is not offered
// for 3D runs yet (an error). The session is started here and stopped before returning.
template <class Session>
kernel::Result<RunResult> run_organism(Session& session, kernel::VirtualTimeExecutor* virtual_time,
                                       const sim::Scenario& scenario, const RunOptions& options, RunResult result) {
  if (options.shell.kind != ShellRequest::Kind::kNone)
    return kernel::Error{"--shell: not offered for 3D scenarios yet (" + scenario.file + ")"};
  result.seed = session.seed();
  const bool write_files = !result.out_dir.empty();
  std::ofstream probes_csv;
  if (write_files) {
    std::error_code ec;
    std::filesystem::create_directories(result.out_dir, ec);
    if (ec) return kernel::Error{"cannot create " + result.out_dir.string() + ": " + ec.message()};
    probes_csv.open(result.out_dir / "probes.csv", std::ios::binary);
    if (!probes_csv) return kernel::Error{"cannot write " + (result.out_dir / "probes.csv").string()};
  }
  OrganismRecorder recorder(session.runner(), organism_recorder_options(scenario, options, result.seed));
  ProbeRecorder probes(write_files ? &probes_csv : nullptr);
  std::vector<os::Node*> nodes;
  std::vector<std::string> names;
  for (std::size_t i = 0; i < session.robot_count(); ++i) {
    nodes.push_back(&session.robot(i).node());
    names.push_back(nodes.back()->name());  // a module's node is named after it
  }
  // The web view hears every sample too, once it is there (under --realtime from the tasks' threads).
  std::atomic<view::LiveView*> live_view{nullptr};
  const os::ProbeSink to_files = write_files ? probes.sink() : os::ProbeSink{};
  if (write_files || options.view.on)
    for (os::Node* n : nodes)
      n->set_probe_sink([&live_view, to_files](const os::ProbeSample& s) {
        if (view::LiveView* v = live_view.load(std::memory_order_acquire)) v->on_probe(s);
        if (to_files) to_files(s);
      });
  struct ProbeSinkGuard {  // the sinks point at `probes`, which goes before the session
    std::vector<os::Node*>& nodes;
    ~ProbeSinkGuard() {
      for (os::Node* n : nodes) n->set_probe_sink({});
    }
  } probe_sink_guard{nodes};
  // Made last, so that it goes first (its shell sessions live on the modules' nodes).
  std::optional<RunControl> control;
  if (virtual_time) control.emplace(options.speed, scenario.control_period);
  std::unique_ptr<view::LiveView> live;
  if (options.view.on) {
    auto started = view::LiveView::start(view::organism_view_target(session.runner(), names, nodes), scenario.name,
                                         std::chrono::duration<double>(scenario.duration).count(),
                                         control ? &*control : nullptr, view::live_view_options(options.view));
    if (!started) return kernel::Error{started.error()};
    live = std::move(started).value();
    live_view.store(live.get(), std::memory_order_release);
    if (options.on_notice) options.on_notice("view: " + live->url());
  }

  const auto wall_start = std::chrono::steady_clock::now();
  result.planned_seconds = std::chrono::duration<double>(scenario.duration).count();
  session.start();
  result.interrupted = run_slices(
      {.virtual_time = virtual_time,
       .duration = scenario.duration,
       .speed = options.speed,
       .wall_start = wall_start,
       .on_progress = options.on_progress,
       .stop_requested = options.stop_requested,
       .failed = [&session] { return !session.cycle_error().empty() || !session.runner().error().empty(); },
       .control = live && control ? &*control : nullptr,
       .between_slices = live ? std::function<void()>([&live] { live->between_slices(); }) : std::function<void()>()});
  if (live) live->finish();
  session.stop();
  live_view.store(nullptr, std::memory_order_release);
  live.reset();
  result.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  fill_organism_result(recorder, result);
  if (write_files) {
    probes_csv.close();
    if (!probes_csv) return kernel::Error{"cannot write " + (result.out_dir / "probes.csv").string()};
    if (auto st = write_organism_files(recorder, probes, nodes, scenario, result); !st)
      return kernel::Error{st.error()};
  }
  // A failed world (MuJoCo diverged) or a cycle of answers ends the run with its error, after the
  // files of what was run are written.
  std::string e = session.cycle_error();
  if (e.empty()) e = session.runner().error();
  if (!e.empty())
    return kernel::Error{e + (write_files ? "; the run so far is in " + result.out_dir.string() : std::string())};
  return result;
}

}  // namespace symb::apps::run
