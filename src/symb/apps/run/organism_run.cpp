#include "symb/apps/run/organism_run.hpp"

#include <sstream>

#include "symb/apps/cli_args.hpp"
#include "symb/apps/run/probe_plot.hpp"
#include "symb/apps/text_file.hpp"
#include "symb/os/syslog.hpp"

namespace symb::apps::run {

namespace {

namespace fs = std::filesystem;

constexpr std::size_t kMaxProbeCharts = 48;
// Hormone levels side by side per module: charts for the first few hormones of each kind.
constexpr std::size_t kMaxModuleChartValues = 4;

}  // namespace

OrganismRecorderOptions organism_recorder_options(const sim::Scenario& scenario, const RunOptions& options,
                                                  std::uint64_t seed) {
  OrganismRecorderOptions o;
  o.every = options.csv_every;
  o.caption = scenario.name + ", seed " + std::to_string(seed);
  return o;
}

void fill_organism_result(const OrganismRecorder& recorder, RunResult& result) {
  const OrganismSummary s = recorder.summary();
  result.steps = s.ticks;
  result.simulated_seconds = s.seconds;
  result.real_time_factor = result.wall_seconds > 0 ? result.simulated_seconds / result.wall_seconds : 0;
  result.trajectory_hash = s.hash;
  result.organism = std::to_string(s.latches) + " latched, " + std::to_string(s.unlatches) + " unlatched, " +
                    std::to_string(s.refusals) + " refused; final topology " + s.final_components +
                    "; its centre moved " + fixed(s.centre_distance, 2) + " m";
  result.robots.clear();
  const auto samples = recorder.samples();
  const auto& names = recorder.module_names();
  for (std::size_t m = 0; m < names.size(); ++m) {
    RobotSummary r;
    r.name = names[m];
    r.distance = 100 * s.module_distance[m];  // RobotSummary is in cm
    if (!samples.empty() && m < samples.back().modules.size()) {
      const auto& pose = samples.back().modules[m].pose;
      r.end = {100 * pose.position[0], 100 * pose.position[1], pose.yaw()};
    }
    result.robots.push_back(r);
  }
}

kernel::Status write_organism_files(OrganismRecorder& recorder, const ProbeRecorder& probes,
                                    const std::vector<os::Node*>& nodes, const sim::Scenario& scenario,
                                    RunResult& result) {
  std::ostringstream header;
  header << "scenario: " << scenario.name << " (" << scenario.file << ")\n"
         << "world: MuJoCo (3D), " << recorder.module_names().size() << " modules\n"
         << "seed: " << result.seed << "\n"
         << "executor: " << (result.realtime ? "threads, wall clock" : "virtual time") << "\n"
         << "control period: " << fixed(std::chrono::duration<double>(scenario.control_period).count() * 1000, 1)
         << " ms\n"
         << "simulated: " << fixed(result.simulated_seconds, 2) << " s\n";
  if (result.interrupted)
    header << "interrupted: at " << fixed(result.simulated_seconds, 2) << " s of " << fixed(result.planned_seconds, 2)
           << " s (a stop was requested: Ctrl-C or SIGTERM)\n";
  header << "wall clock: " << fixed(result.wall_seconds, 3) << " s\n"
         << "real-time factor: " << fixed(result.real_time_factor, 1) << "\n"
         << "trajectory hash: " << hex64(result.trajectory_hash) << "\n";
  auto files = recorder.finish(result.out_dir, header.str());
  if (!files) return kernel::Error{files.error()};
  result.files = std::move(files).value();
  result.files.push_back(result.out_dir / "probes.csv");

  std::ostringstream logs;
  for (os::Node* node : nodes)
    for (const os::LogEntry& e : node->log().since(0)) logs << node->name() << " " << os::format_log_entry(e) << "\n";
  if (auto st = write_file(result.out_dir / "syslog.txt", logs.str()); !st) return st;
  result.files.push_back(result.out_dir / "syslog.txt");

  auto charts = write_probe_charts(result.out_dir / "probes", probes, kMaxProbeCharts);
  if (!charts) return kernel::Error{charts.error()};
  result.files.insert(result.files.end(), charts->begin(), charts->end());
  // One module alone: its own chart in probes/ says it all.
  const std::vector<ProbeSeries> side_by_side = module_series(probes, "hormones/", kMaxModuleChartValues);
  std::vector<const ProbeSeries*> shown;
  for (const ProbeSeries& s : side_by_side)
    if (s.width >= 2) shown.push_back(&s);
  auto module_charts = write_charts(result.out_dir / "modules", shown);
  if (!module_charts) return kernel::Error{module_charts.error()};
  result.files.insert(result.files.end(), module_charts->begin(), module_charts->end());
  return {};
}

}  // namespace symb::apps::run
