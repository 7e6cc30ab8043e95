// OrganismRecorder: what a 3D run of docking modules (sim/mujoco) keeps for the person afterwards,
// the counterpart of the 2D RunRecorder. It watches a MujocoRunner (an observer, on the runner's
// context, once per control period) and the world's docking log, and finish() writes into the
// run's output folder:
//   paths_top.svg, paths_side.svg  every module's path seen from above (x-y) and from the side
//                  (x-z), its box at its end pose, docked pairs joined (organism_svg.hpp)
//   poses.csv      time_s,step,module,x_m,y_m,z_m,qw,qx,qy,qz,yaw_rad,wheel_l_m_s,wheel_r_m_s:
//                  a row per module and kept sample (wheels: the rim speeds commanded)
//   joints.csv     time_s,step,module,angle_rad,target_rad,speed_rad_s: the hinge, likewise
//   joints.svg     every module's hinge angle over time, a line per module
//   docking.csv    step,time_s,change,connector,other,distance_m,angle_rad,reason: the world's
//                  whole docking log (latched, unlatched, refused; "a.front"; the reason quoted)
//   docking.svg    the same on a timeline, a lane per module
//   topology.csv   time_s,step,event,docked_pairs,components,component_count: a row at the start
//                  and one per latch or unlatch, giving who is docked to whom from then on
//                  ("a.front=b.back", space-separated) and the docked groups ("a+b c")
//   topology.svg   a lane per module coloured by its docked group
//   world.xml      the model's MJCF text: `simulate world.xml` (MuJoCo's viewer) opens it
//   summary.txt    the caller's header lines, then: the distance the organism's centre (the
//                  modules' mean position) moved, per module distances, the docks and undocks
//                  and the final topology
//
// Sampling: every `every`-th control tick is kept; when `max_samples` are kept, every other one
// is dropped and from then on every 2 * every-th tick is kept (again and again), so a run of any
// length keeps at most max_samples evenly spaced samples (CSV rows per module and path points).
// The last tick is always kept. Distances are summed over every tick, and the docking log and
// the topology are complete, whatever the sampling.
//
// Threads: the observer and finish() share the recorder's state under its lock, so finish() may
// run while the runner still ticks (Ctrl-C): it writes what was recorded until then. The observer
// holds that state, not the recorder: the recorder may go before the runner.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "symb/apps/run/organism_svg.hpp"
#include "symb/kernel/result.hpp"
#include "symb/sim/mujoco/mujoco_runner.hpp"

namespace symb::apps::run {

struct OrganismRecorderOptions {
  std::uint32_t every = 1;         // keep at most every n-th tick (symb run --csv-every)
  std::size_t max_samples = 4096;  // kept samples at most (>= 2)
  std::string caption;             // in the pictures' titles: "scenario, seed 7"
};

struct OrganismSample {
  std::uint64_t step = 0;  // the world's step count
  double time = 0;         // s, the tick's node time
  std::vector<sim::mujoco::ModuleStep> modules;
};

struct TopologyRow {
  double time = 0;  // s
  std::uint64_t step = 0;
  std::string event;                   // "start", or "latched a.front b.back"
  std::vector<DockedPair> pairs;       // sorted
  std::vector<std::size_t> component;  // per module: its group's first module
};

struct OrganismSummary {
  double seconds = 0;                   // the last tick's time
  std::uint64_t ticks = 0;              // control ticks seen
  double centre_distance = 0;           // m: the path length of the modules' mean position (x-y)
  double centre_displacement = 0;       // m: from its first to its last place (x-y)
  std::vector<double> module_distance;  // m per module (x-y path length)
  std::size_t latches = 0, unlatches = 0, refusals = 0;
  std::string final_components;  // "a+b c"
  // FNV-1a over every module's pose, hinge angle and speed and wheel commands at every tick:
  // equal hashes, equal runs.
  std::uint64_t hash = 0xcbf29ce484222325ULL;
};

class OrganismRecorder {
 public:
  // Reads the world's names, sizes, MJCF text, docking log and dock state now (through
  // with_world) and attaches itself to the runner as an observer. Before or after start().
  explicit OrganismRecorder(sim::mujoco::MujocoRunner& runner, OrganismRecorderOptions options = {});
  ~OrganismRecorder();
  OrganismRecorder(const OrganismRecorder&) = delete;
  OrganismRecorder& operator=(const OrganismRecorder&) = delete;

  // Writes the files above into `dir` (made when missing) for what was recorded so far, with
  // `summary_header` (lines about the run: scenario, seed, executor) first in summary.txt.
  // Returns the paths written, or the first write that failed.
  kernel::Result<std::vector<std::filesystem::path>> finish(const std::filesystem::path& dir,
                                                            std::string_view summary_header = {});

  // What was gathered so far (copies, under the lock).
  std::vector<OrganismSample> samples() const;
  std::vector<sim::mujoco::DockEvent> docking_log() const;
  std::vector<TopologyRow> topology() const;
  OrganismSummary summary() const;
  const std::vector<std::string>& module_names() const;
  // "a+b c": the groups of `component` (TopologyRow::component) by name.
  std::string components_text(const std::vector<std::size_t>& component) const;

 private:
  struct State;
  std::shared_ptr<State> s_;
};

}  // namespace symb::apps::run
