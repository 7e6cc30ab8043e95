// `symb run`'s 3D output: an OrganismRecorder on a MujocoRunner of three cubes (virtual time)
// while two of them latch and unlatch and a third drives off and is refused a latch, then the
// files: docking.csv row for row the world's docking log, topology.csv changing at the latch and
// the unlatch, poses.csv and joints.csv the runner's records, the path pictures one polyline per
// module with a point per kept sample, world.xml compiling again to the same model. The sampling
// rule keeps a bounded, evenly spaced record; finish() mid-run writes what was recorded so far;
// run_organism drives a session-like object in slices and stops on request. Figures written
// beside their bounds were measured once with this file (release build).
#include "symb/apps/run/organism_run.hpp"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "symb/apps/run/organism_recorder.hpp"
#include "symb/apps/run/probe_plot.hpp"
#include "symb/apps/run/probe_recorder.hpp"
#include "symb/apps/text_file.hpp"
#include "symb/kernel/thread_executor.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/sim/mujoco/mjcf_file.hpp"
#include "symb/sim/mujoco/mujoco_runner.hpp"
#include "symb/sim/robot_system.hpp"

#include "support/eventually.hpp"
#include "support/measured.hpp"

namespace symb::apps::run {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using sim::mujoco::MujocoRunner;
using sim::mujoco::MujocoWorld;

constexpr kernel::Duration kOrgPeriod = 30ms;

fs::path org_temp_dir(const std::string& tag) {
  const fs::path dir = fs::temp_directory_path() / ("symb_organism_" + tag + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  return dir;
}

std::vector<std::vector<std::string>> org_read_csv(const fs::path& file) {
  auto text = read_file(file);
  EXPECT_TRUE(text.ok()) << text.error();
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(text.ok() ? *text : std::string());
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> cells;
    std::string cell;
    bool quoted = false;
    for (char c : line) {
      if (c == '"')
        quoted = !quoted;
      else if (c == ',' && !quoted)
        cells.push_back(std::move(cell)), cell.clear();
      else
        cell += c;
    }
    cells.push_back(cell);
    rows.push_back(std::move(cells));
  }
  return rows;
}

std::size_t org_count(const std::string& text, const std::string& part) {
  std::size_t n = 0;
  for (auto at = text.find(part); at != std::string::npos; at = text.find(part, at + part.size())) ++n;
  return n;
}

// The points of every `<polyline class="path" ...>` of an SVG, per module name.
std::map<std::string, std::size_t> org_path_points(const std::string& svg) {
  std::map<std::string, std::size_t> out;
  const std::string tag = "<polyline class=\"path\" data-module=\"";
  for (auto at = svg.find(tag); at != std::string::npos; at = svg.find(tag, at + 1)) {
    const auto name_end = svg.find('"', at + tag.size());
    const std::string name = svg.substr(at + tag.size(), name_end - at - tag.size());
    const auto p = svg.find("points=\"", name_end) + 8;
    const auto q = svg.find('"', p);
    std::istringstream pts(svg.substr(p, q - p));
    std::size_t n = 0;
    for (std::string pt; pts >> pt;) ++n;
    out[name] = n;
  }
  return out;
}

// Three standard cubes: a and b front to front 5 mm apart (latchable), c 0.4 m to the side.
struct OrgRig {
  kernel::VirtualTimeExecutor ex;
  MujocoWorld world;
  std::unique_ptr<MujocoRunner> runner;

  static MujocoWorld make() {
    const auto kind = sim::mujoco::standard_kind();
    auto made = MujocoWorld::make({{"a", kind, {0, 0, 0}},
                                   {"b", kind, {kind.body.size[0] + 0.005, 0, std::numbers::pi}},
                                   {"c", kind, {0, 0.4, 0}}});
    EXPECT_TRUE(made.ok()) << made.error();
    return std::move(made).value();
  }
  OrgRig() : world(make()) {
    runner = std::make_unique<MujocoRunner>(ex, world, sim::PeriodicRunner::Options{.period = kOrgPeriod});
    // c bends its hinge and drives straight ahead.
    EXPECT_TRUE(runner->hinge(2)->open().ok());
    EXPECT_TRUE(runner->hinge(2)->set(std::vector<float>{0.4f}).ok());
    EXPECT_TRUE(runner->wheels(2)->open().ok());
    EXPECT_TRUE(runner->wheels(2)->set(std::vector<float>{500, 500}).ok());
  }
  std::string last_error;
  // Latches (or unlatches) module m's connector `name` between ticks, as a shell would.
  bool dock(std::size_t m, const char* name, bool latch) {
    bool ok = false;
    runner->with_world([&](MujocoWorld& w) {
      const auto c = *w.find_connector(m, name);
      const auto st = latch ? w.latch(m, c) : w.unlatch(m, c);
      ok = st.ok();
      if (!ok) last_error = st.error();
    });
    return ok;
  }
};

TEST(OrganismRecorder, WritesPathsTopologyDockingJointsAndAWorldThatCompilesAgain) {
  OrgRig rig;
  OrganismRecorder recorder(*rig.runner, {.every = 1, .max_samples = 4096, .caption = "three cubes"});
  std::vector<sim::mujoco::MujocoStepRecord> records;
  rig.runner->add_observer([&](const sim::mujoco::MujocoStepRecord& r) { records.push_back(r); });
  ASSERT_TRUE(rig.runner->start());
  rig.ex.run_for(300ms);
  ASSERT_TRUE(rig.dock(1, "front", true)) << rig.last_error;
  ASSERT_FALSE(rig.dock(2, "front", true));  // nothing in front of c: refused
  const double latched_at = rig.world.time();
  rig.ex.run_for(600ms);
  ASSERT_TRUE(rig.dock(0, "front", false));
  const double unlatched_at = rig.world.time();
  rig.ex.run_for(300ms);
  rig.runner->stop();
  ASSERT_EQ(records.size(), 40U);  // 1.2 s at 30 ms

  const fs::path out = org_temp_dir("files");
  auto files = recorder.finish(out, "scenario: three cubes\n");
  ASSERT_TRUE(files.ok()) << files.error();
  EXPECT_EQ(files->size(), 11U);

  // docking.csv: the world's log, row for row.
  const auto& log = rig.world.docking_log();
  ASSERT_EQ(log.size(), 3U);
  const auto docking = org_read_csv(out / "docking.csv");
  ASSERT_EQ(docking.size(), 4U);
  EXPECT_EQ(docking[0][0], "step");
  const char* changes[] = {"latched", "refused", "unlatched"};
  for (std::size_t i = 0; i < log.size(); ++i) {
    const auto& row = docking[i + 1];
    ASSERT_EQ(row.size(), 8U) << i;
    EXPECT_EQ(row[0], std::to_string(log[i].step));
    EXPECT_EQ(row[2], changes[i]);
    EXPECT_EQ(row[7], log[i].reason);
    const auto name = [&](std::size_t m, std::size_t c) {
      return m == sim::mujoco::kNoIndex ? std::string()
                                        : rig.world.module(m).name + "." + rig.world.module(m).kind.connectors[c].name;
    };
    EXPECT_EQ(row[3], name(log[i].module, log[i].connector));
    EXPECT_EQ(row[4], name(log[i].other_module, log[i].other_connector));
  }
  EXPECT_EQ(docking[1][3], "b.front");
  EXPECT_EQ(docking[1][4], "a.front");
  EXPECT_NEAR(std::stod(docking[1][5]), log[0].distance, 1e-5);
  EXPECT_NEAR(std::stod(docking[1][5]), 0.005, 0.002);  // the gap the modules were set down with
  EXPECT_EQ(docking[2][3], "c.front");

  // topology.csv: alone, then a+b from the latch, then alone again from the unlatch.
  const auto topo = org_read_csv(out / "topology.csv");
  ASSERT_EQ(topo.size(), 4U);
  EXPECT_EQ(topo[1][2], "start");
  EXPECT_EQ(topo[1][4], "a b c");
  EXPECT_EQ(topo[1][5], "3");
  EXPECT_NEAR(std::stod(topo[2][0]), latched_at, 1e-3);
  EXPECT_EQ(topo[2][2], "latched b.front a.front");
  EXPECT_EQ(topo[2][3], "a.front=b.front");
  EXPECT_EQ(topo[2][4], "a+b c");
  EXPECT_EQ(topo[2][5], "2");
  EXPECT_NEAR(std::stod(topo[3][0]), unlatched_at, 1e-3);
  EXPECT_EQ(topo[3][3], "");
  EXPECT_EQ(topo[3][4], "a b c");

  // poses.csv and joints.csv: a row per module and tick, the runner's own records.
  const auto poses = org_read_csv(out / "poses.csv");
  const auto joints = org_read_csv(out / "joints.csv");
  ASSERT_EQ(poses.size(), 1 + 3 * records.size());
  ASSERT_EQ(joints.size(), 1 + 3 * records.size());
  for (std::size_t t = 0; t < records.size(); ++t)
    for (std::size_t m = 0; m < 3; ++m) {
      const auto& p = poses[1 + 3 * t + m];
      const auto& j = joints[1 + 3 * t + m];
      const auto& r = records[t].modules[m];
      ASSERT_EQ(p[1], std::to_string(records[t].step));
      EXPECT_EQ(p[2], std::string(1, static_cast<char>('a' + m)));
      for (std::size_t k = 0; k < 3; ++k) EXPECT_NEAR(std::stod(p[3 + k]), r.pose.position[k], 6e-6);
      for (std::size_t k = 0; k < 4; ++k) EXPECT_NEAR(std::stod(p[6 + k]), r.pose.quaternion[k], 6e-7);
      EXPECT_NEAR(std::stod(j[3]), r.hinge_angle, 6e-6);
      EXPECT_NEAR(std::stod(j[4]), r.hinge_target, 6e-6);
      EXPECT_NEAR(std::stod(j[5]), r.hinge_speed, 6e-6);
    }
  // The last rows are the world's end state.
  for (std::size_t m = 0; m < 3; ++m)
    EXPECT_NEAR(std::stod(poses[poses.size() - 3 + m][3]), rig.world.pose(m).position[0], 6e-6);
  // c's hinge went to its target; c drove off along x (measured: 0.395 rad, 0.160 m).
  EXPECT_TRUE(symb::testing::near_measured(std::stod(joints.back()[3]), 0.395, 0.01)) << joints.back()[3];
  const double c_moved = rig.world.pose(2).position[0];
  EXPECT_TRUE(symb::testing::near_measured(c_moved, 0.160, 0.01)) << c_moved;

  // The pictures: a polyline per module, the start and a point per tick.
  for (const char* name : {"paths_top.svg", "paths_side.svg"}) {
    auto svg = read_file(out / name);
    ASSERT_TRUE(svg.ok()) << svg.error();
    const auto points = org_path_points(*svg);
    ASSERT_EQ(points.size(), 3U) << name;
    for (const auto& [module, n] : points) EXPECT_EQ(n, 1 + records.size()) << name << " " << module;
    EXPECT_EQ(org_count(*svg, "class=\"dock\""), 0U) << name;  // undocked at the end
  }
  auto topo_svg = read_file(out / "topology.svg");
  ASSERT_TRUE(topo_svg.ok());
  EXPECT_EQ(org_count(*topo_svg, "class=\"span\""), 9U);  // 3 spans x 3 modules
  auto dock_svg = read_file(out / "docking.svg");
  ASSERT_TRUE(dock_svg.ok());
  EXPECT_EQ(org_count(*dock_svg, "class=\"latched\""), 2U);
  EXPECT_EQ(org_count(*dock_svg, "class=\"unlatched\""), 2U);
  EXPECT_EQ(org_count(*dock_svg, "class=\"refused\""), 1U);
  auto joints_svg = read_file(out / "joints.svg");
  ASSERT_TRUE(joints_svg.ok());
  EXPECT_EQ(org_count(*joints_svg, "<polyline"), 3U);

  // world.xml compiles with MuJoCo's file loader into the model the world runs.
  auto saved = sim::mujoco::load_mjcf_file(out / "world.xml");
  ASSERT_TRUE(saved.ok()) << saved.error();
  auto running = sim::mujoco::mjcf_counts(rig.world.mjcf());
  ASSERT_TRUE(running.ok()) << running.error();
  EXPECT_EQ(*saved, *running);
  EXPECT_EQ(saved->degrees_of_freedom, rig.world.degrees_of_freedom());
  EXPECT_EQ(saved->degrees_of_freedom, 27U);  // 3 x (free joint 6, hinge, two wheels)
  EXPECT_GE(saved->bodies, 1 + 3 * 4U);       // the world, and per module base, tail and two wheels

  auto summary = read_file(out / "summary.txt");
  ASSERT_TRUE(summary.ok());
  EXPECT_EQ(summary->rfind("scenario: three cubes\nmodules: 3\n", 0), 0U) << *summary;
  EXPECT_NE(summary->find("docking: 1 latched, 1 unlatched, 1 refused\n"), std::string::npos) << *summary;
  EXPECT_NE(summary->find("final topology: a b c\n"), std::string::npos) << *summary;
  // The centre moved by a third of c's run (a and b stay put).
  const OrganismSummary s = recorder.summary();
  EXPECT_NEAR(s.centre_displacement, c_moved / 3, 0.01);
  EXPECT_GE(s.centre_distance, s.centre_displacement);
  EXPECT_EQ(s.ticks, records.size());
  fs::remove_all(out);
}

TEST(OrganismRecorder, AFaultyPathIsReportedNotThrown) {
  OrgRig rig;
  OrganismRecorder recorder(*rig.runner);
  const fs::path blocker = org_temp_dir("blocker");
  ASSERT_TRUE(write_file(blocker, "a file where the folder should be").ok());
  auto files = recorder.finish(blocker / "out");
  ASSERT_FALSE(files.ok());
  EXPECT_NE(files.error().find(blocker.string()), std::string::npos) << files.error();
  fs::remove(blocker);
}

TEST(OrganismRecorder, ASavedModelThatDoesNotCompileIsAnErrorNamingTheFile) {
  const fs::path bad = org_temp_dir("bad") += ".xml";
  ASSERT_TRUE(write_file(bad, "<mujoco><worldbody><body><geom type=\"box\"/></body></worldbody>").ok());
  auto counts = sim::mujoco::load_mjcf_file(bad);
  ASSERT_FALSE(counts.ok());
  EXPECT_EQ(counts.error().rfind(bad.string() + ": MuJoCo could not compile it: ", 0), 0U) << counts.error();
  fs::remove(bad);
  auto missing = sim::mujoco::load_mjcf_file(bad);
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.error(), bad.string() + ": no such file");
}

TEST(OrganismRecorder, KeepsAtMostMaxSamplesEvenlySpacedAndTheLastTick) {
  OrgRig rig;
  OrganismRecorder recorder(*rig.runner, {.every = 2, .max_samples = 8, .caption = ""});
  ASSERT_TRUE(rig.runner->start());
  rig.ex.run_for(3s);  // 100 ticks
  rig.runner->stop();
  const auto samples = recorder.samples();
  // Every 2nd tick until 8 are kept, then every 4th, 8th, 16th: ticks 0, 16, ..., 96, and the last.
  ASSERT_EQ(samples.size(), 8U);
  const std::uint64_t ticks_step = 15;  // world steps per 30 ms tick
  for (std::size_t i = 0; i + 1 < samples.size(); ++i) EXPECT_EQ(samples[i].step, (16 * i + 1) * ticks_step) << i;
  EXPECT_EQ(samples.back().step, rig.world.steps());
  EXPECT_EQ(recorder.summary().ticks, 100U);
}

TEST(OrganismRecorder, FinishMidRunWritesWhatWasRecordedAndTheRecorderMayGoFirst) {
  OrgRig rig;
  auto recorder = std::make_unique<OrganismRecorder>(*rig.runner);
  ASSERT_TRUE(rig.runner->start());
  rig.ex.run_for(300ms);
  const fs::path out = org_temp_dir("midrun");
  auto files = recorder->finish(out);
  ASSERT_TRUE(files.ok()) << files.error();
  EXPECT_EQ(org_read_csv(out / "joints.csv").size(), 1 + 3 * 10U);
  recorder.reset();       // the runner's observer keeps the state alive
  rig.ex.run_for(300ms);  // and ticks on without it
  EXPECT_EQ(rig.world.steps(), 300U);
  fs::remove_all(out);
}

TEST(OrganismRecorder, FinishWhileTheRunnerTicksOnItsOwnThread) {
  // symb run --realtime and Ctrl-C: the runner ticks on the thread executor while finish() writes
  // from this thread; a latch from here lands in the files too.
  kernel::ThreadExecutor ex;
  MujocoWorld world = OrgRig::make();
  auto runner = std::make_unique<MujocoRunner>(ex, world, sim::PeriodicRunner::Options{.period = kOrgPeriod});
  OrganismRecorder recorder(*runner);
  ASSERT_TRUE(runner->start());
  bool latched = false;
  runner->with_world([&](MujocoWorld& w) { latched = w.latch(1, *w.find_connector(1, "front")).ok(); });
  ASSERT_TRUE(latched);
  // Waited for, not slept for: on a busy box the runner's thread may get few of its ticks.
  symb::testing::eventually([&] { return recorder.summary().ticks >= 5; });
  const fs::path out = org_temp_dir("threads");
  auto files = recorder.finish(out);
  ASSERT_TRUE(files.ok()) << files.error();
  const auto joints = org_read_csv(out / "joints.csv");
  EXPECT_GE(joints.size(), 1 + 3 * 5U);
  EXPECT_EQ((joints.size() - 1) % 3, 0U);  // whole ticks only
  const auto topo = org_read_csv(out / "topology.csv");
  ASSERT_GE(topo.size(), 3U);
  EXPECT_EQ(topo[2][4], "a+b c");
  runner.reset();  // stops it; the executor goes after
  fs::remove_all(out);
}

// A session-like object (the organism session's API) over the rig: a node per module, each with
// a task that probes hormone levels growing along the chain.
class OrgHormones final : public os::Task {
 public:
  explicit OrgHormones(float level) : level_(level) {}

 protected:
  void on_tick() override { probe("hormones/c0", {level_, 2 * level_}); }

 private:
  float level_;
};

struct OrgRobot {
  std::unique_ptr<os::Node> n;
  os::Node& node() { return *n; }
};

struct OrgSession {
  OrgRig& rig;
  std::vector<OrgRobot> robots;
  explicit OrgSession(OrgRig& r) : rig(r) {
    for (std::size_t m = 0; m < rig.world.module_count(); ++m) {
      robots.push_back(
          {std::make_unique<os::Node>(rig.ex, os::NodeConfig{rig.world.module(m).name, sim::robot_node_seed(7, m)})});
      rig.runner->set_node(m, robots.back().n.get());
      os::TaskOptions options;
      options.period = kOrgPeriod;
      EXPECT_TRUE(
          robots.back().n->create("ahhs", std::make_unique<OrgHormones>(static_cast<float>(m + 1)), options).ok());
    }
  }
  ~OrgSession() {
    for (std::size_t m = 0; m < robots.size(); ++m) rig.runner->set_node(m, nullptr);
  }
  void start() { EXPECT_TRUE(rig.runner->start()); }
  void stop() { rig.runner->stop(); }
  std::uint64_t seed() const { return 7; }
  std::string cycle_error() const { return {}; }
  std::size_t robot_count() const { return robots.size(); }
  OrgRobot& robot(std::size_t i) { return robots.at(i); }
  MujocoRunner& runner() { return *rig.runner; }
};

TEST(OrganismRun, RunsASessionInSlicesStopsOnRequestAndWritesTheFolder) {
  OrgRig rig;
  OrgSession session(rig);
  sim::Scenario scenario;
  scenario.name = "cubes";
  scenario.file = "cubes.yaml";
  scenario.duration = 3s;
  RunOptions options;
  int polls = 0;
  options.stop_requested = [&polls] { return ++polls > 1; };  // Ctrl-C after the first slice (1 s)
  RunResult result;
  result.out_dir = org_temp_dir("run");
  auto run = run_organism(session, &rig.ex, scenario, options, result);
  ASSERT_TRUE(run.ok()) << run.error();
  EXPECT_TRUE(run->interrupted);
  EXPECT_EQ(run->steps, 33U);  // 1 s at 30 ms
  EXPECT_NEAR(run->simulated_seconds, 0.99, 1e-9);
  EXPECT_EQ(run->planned_seconds, 3.0);
  EXPECT_EQ(run->seed, 7U);
  ASSERT_EQ(run->robots.size(), 3U);
  EXPECT_EQ(run->robots[2].name, "c");
  EXPECT_EQ(run->organism.rfind("0 latched, 0 unlatched, 0 refused; final topology a b c; its centre moved ", 0), 0U)
      << run->organism;
  EXPECT_TRUE(symb::testing::near_measured(run->robots[2].distance, 13.20, 1.0));  // cm: c drove (measured)
  for (const char* name : {"world.xml", "summary.txt", "probes.csv", "syslog.txt", "topology.csv"})
    EXPECT_TRUE(fs::exists(run->out_dir / name)) << name;
  auto summary = read_file(run->out_dir / "summary.txt");
  ASSERT_TRUE(summary.ok());
  EXPECT_NE(summary->find("world: MuJoCo (3D), 3 modules\n"), std::string::npos) << *summary;
  EXPECT_NE(summary->find("interrupted: at 0.99 s of 3.00 s"), std::string::npos) << *summary;
  // The hormone levels side by side: a chart per hormone, a line per module.
  for (const char* chart : {"modules.ahhs.hormones_c0.v0.svg", "modules.ahhs.hormones_c0.v1.svg"}) {
    auto svg = read_file(run->out_dir / "modules" / chart);
    ASSERT_TRUE(svg.ok()) << chart;
    EXPECT_EQ(org_count(*svg, "<polyline"), 3U) << chart;
    for (const char* m : {">a</text>", ">b</text>", ">c</text>"}) EXPECT_NE(svg->find(m), std::string::npos) << m;
  }
  EXPECT_TRUE(fs::exists(run->out_dir / "probes" / "a.ahhs.hormones_c0.svg"));
  // Same seed, same run.
  OrgRig again_rig;
  OrgSession again(again_rig);
  RunOptions quick;
  quick.stop_requested = [&polls] { return ++polls > 3; };
  auto second = run_organism(again, &again_rig.ex, scenario, quick, RunResult{});
  ASSERT_TRUE(second.ok()) << second.error();
  EXPECT_EQ(second->steps, run->steps);
  EXPECT_EQ(second->trajectory_hash, run->trajectory_hash);
  fs::remove_all(run->out_dir);
}

}  // namespace
}  // namespace symb::apps::run

namespace symb::apps::run {
namespace {

// Feeds `recorder` one sample of (robot, task, channel, values) at time t.
void probe_sample(ProbeRecorder& recorder, double t, std::string_view robot, std::string_view task,
                  std::string_view channel, std::vector<float> values) {
  os::ProbeSample s;
  s.time = std::chrono::duration_cast<kernel::Time>(std::chrono::duration<double>(t));
  s.node = robot;
  s.task = task;
  s.channel = channel;
  s.values = values;
  recorder.record(s);
}

TEST(ModuleSeries, OneCompartmentPerModuleIsOneChartAndAWholeNetworkPerRobotIsNot) {
  ProbeRecorder recorder(nullptr);
  for (int k = 0; k < 3; ++k) {
    // Modules m0..m2 each step compartment k of one network: one gradient chart.
    for (int m = 0; m < 3; ++m)
      probe_sample(recorder, k, "m" + std::to_string(m), "hormones", "hormones/c" + std::to_string(m),
                   {static_cast<float>(m + k)});
    // Robots a and b each run a whole two-compartment network: one chart per compartment.
    for (const char* r : {"a", "b"})
      for (int c = 0; c < 2; ++c) probe_sample(recorder, k, r, "ahhs", "hormones/c" + std::to_string(c), {1.0f});
  }
  const auto series = module_series(recorder, "hormones/", 4);
  std::vector<std::string> names;
  for (const auto& s : series) names.push_back(s.task + " " + s.channel + " " + std::to_string(s.labels.size()));
  EXPECT_EQ(names,
            (std::vector<std::string>{"hormones hormones/*.v0 3", "ahhs hormones/c0.v0 2", "ahhs hormones/c1.v0 2"}));
  ASSERT_FALSE(series.empty());
  EXPECT_EQ(series[0].labels, (std::vector<std::string>{"m0", "m1", "m2"}));
}

}  // namespace
}  // namespace symb::apps::run
