// Running a scenario in-process (`symb run`): the scenario session in deterministic virtual time
// (a 2D one on the lockstep executor, its robots' nodes on `threads` worker threads, the same run
// for any number, or with one robot on the virtual-time executor, the same run again; a 3D one on
// the virtual-time executor) or on OS threads with realtime, a
// progress report, an optional command shell on one robot, and what a person wants to look at
// afterwards, in an output folder:
//   trajectory.svg  walls and every robot's path, contacts marked
//   steps.csv       one row per robot and recorded step: time, pose, 7 IR values, wheel speeds,
//                   contact
//   summary.txt     per robot: distance, contacts, time moving; sim speed as real-time factor
//   syslog.txt      every robot's SysLog
//   probes.csv      every sample the controllers publish about themselves (Task::probe)
//   probes/*.svg    a line chart per probed series (robot, task, channel), for the first 48
//   spikes/         spiking networks: an AEDAT 2.0 file, a raster and the grown network's picture
//                   per network task (spike_recorder.hpp)
// More than 100 robots: steps.h5 and density, trails and per-robot pictures instead (run_recording.hpp).
// A 3D scenario writes its own set (organism_run.hpp, organism_recorder.hpp; docs/run.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "symb/apps/run/remote_robots.hpp"
#include "symb/apps/run/run_recorder.hpp"
#include "symb/apps/run/run_recording.hpp"
#include "symb/apps/view/view_request.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"
#include "symb/sim/world_spec.hpp"

namespace symb::apps::run {

struct ShellRequest {
  enum class Kind { kNone, kStdio, kTcp };
  Kind kind = Kind::kNone;
  std::string host = "127.0.0.1";
  std::uint16_t port = 0;  // kTcp: 0 picks a free port
  std::string robot;       // empty: the first robot
  std::string token;       // kTcp: empty makes one up
};

// `symb run --view`: the web view (apps/view/live_view.hpp), 2D and 3D runs.
using view::ViewRequest;

struct RunProgress {
  double simulated_seconds = 0;
  double total_seconds = 0;
  double wall_seconds = 0;
  double fraction() const { return total_seconds > 0 ? simulated_seconds / total_seconds : 1.0; }
};

struct RunOptions {
  std::string scenario_path;
  std::optional<std::uint64_t> seed;
  std::optional<kernel::Duration> duration;
  std::optional<std::filesystem::path> out_dir;    // none: write no files (unless out_under)
  std::optional<std::filesystem::path> out_under;  // without out_dir: write into out_under/<scenario name>
  bool realtime = false;
  // Virtual time, 2D only: worker threads running the robots' nodes between world steps
  // (kernel::LockstepExecutor; the run is the same for any number). 0: default_threads().
  unsigned threads = 0;
  // Virtual time only: 0 runs as fast as possible; s > 0 keeps simulated time at s times the wall
  // clock (a shell needs this: otherwise the run is over before anyone could type).
  double speed = 0;
  ShellRequest shell;
  ViewRequest view;
  // Replaying a champion (--genome): every robot's task named `genome_controller` gets these
  // weights (its `weights` parameter, a network task's flat genome); no such task is an error.
  std::optional<std::string> controller_weights;
  std::string genome_controller = "controller";
  std::uint32_t csv_every = 1;  // record every n-th step in steps.csv (the picture uses every step)
  // 2D: which format the steps are recorded in (steps.csv, steps.h5), and which robots' rows
  // (record_options.hpp); `csv_every` picks the steps for either.
  RecordOptions record;
  // Task-type plugins to load before the scenario is checked (--plugin), besides its own `plugins:`.
  std::vector<std::string> plugins;
  // 2D virtual time: robots whose nodes run in other processes (--bus dds --remote; remote_robots.hpp).
  RemoteRobotsOptions remote;
  std::function<void(const RunProgress&)> on_progress;
  std::function<void(const std::string&)> on_notice;  // "shell: ...", "view: ..." for the person
  // Polled between slices of the run (at most 20 ms of wall clock apart while pacing, one
  // simulated second otherwise): true stops the run there, and what was run is written as for a
  // finished one (RunResult::interrupted).
  std::function<bool()> stop_requested;
};

// Worker threads of a 2D run when none are asked for: one per core from kParallelRobots robots
// on, one below. The result is the same either way; measured on the 2-core reference box, a
// second thread makes 1,000 robots 1.4 times faster and 100 robots 1.4 times slower (waking it
// four times a step costs more than the few microseconds of work it takes over). From the same
// size the lanes' state is prefetched (LockstepExecutor::Options::prefetch): measured, 30 % less
// CPU time at 10,000 robots, the same at 1,000 (whose state stays in the level-3 cache), and a few
// percent more at 100.
inline constexpr std::size_t kParallelRobots = 500;
unsigned default_threads(std::size_t robots);

struct RunResult {
  std::string scenario;
  std::uint64_t seed = 0;
  bool realtime = false;
  unsigned threads = 1;  // the lockstep executor's worker threads (2D virtual time)
  // Whether the robots' nodes ran on the lockstep executor (2D virtual time with more than one
  // robot, remote robots or threads asked for); otherwise on one virtual-time executor.
  bool lockstep = false;
  // 2D virtual time: the share of the run's wall clock spent with the robots' nodes running, the
  // part more threads can shorten (the world's step, radio and recording run on one thread).
  double nodes_share = 0;
  // From kParallelRobots robots (2D virtual time): the heap on huge pages (huge_page_heap.hpp),
  // one line for summary.txt; empty below.
  std::string heap;
  double simulated_seconds = 0;
  double planned_seconds = 0;  // the duration asked for
  bool interrupted = false;    // stopped by stop_requested at simulated_seconds
  double wall_seconds = 0;
  double real_time_factor = 0;
  std::uint64_t steps = 0;
  std::vector<RobotSummary> robots;
  // FNV-1a over every robot's pose and wheel speeds at every step: equal hashes, equal runs.
  std::uint64_t trajectory_hash = 0;
  std::filesystem::path out_dir;
  std::vector<std::filesystem::path> files;
  // A 3D run's organism in one line ("1 latched, 0 unlatched, 0 refused; final topology a+b c");
  // empty for a 2D run. Its robots are then modules: distance and end pose, no contacts.
  std::string organism;
  // A 2D run's recording: format, bytes, wall clock spent (run_recording.hpp).
  RecordFigures recording;
  // --view: the frames queued for the pages, sent, and dropped because a page did not keep up.
  std::uint64_t view_frames = 0, view_frames_sent = 0, view_frames_dropped = 0;
  // --remote: summary.txt's lines on the remote robots (RemoteRobots::summary), and how many were lost.
  std::string remote;
  std::size_t remote_gone = 0;
};

kernel::Result<RunResult> run_scenario(const RunOptions& options);

}  // namespace symb::apps::run
