#include "symb/apps/run/run_recording.hpp"

#include <chrono>
#include <sstream>

#include "symb/apps/text_file.hpp"

namespace symb::apps::run {

namespace fs = std::filesystem;

kernel::Result<std::unique_ptr<RunRecording>> RunRecording::open(const sim::World& world, const sim::Scenario& scenario,
                                                                 std::uint64_t seed, const RecordOptions& options,
                                                                 std::uint32_t every, const fs::path& dir) {
  std::unique_ptr<RunRecording> r(new RunRecording());
  r->dir_ = dir;
  r->seed_ = seed;
  r->dt_ = std::chrono::duration<double>(scenario.control_period).count();
  const std::size_t n = world.robot_count();
  std::vector<std::string> names;
  for (std::size_t i = 0; i < n; ++i) names.push_back(world.robot_name(i));
  RecorderSetup setup;
  setup.every = std::max<std::uint32_t>(1, every);
  if (!options.robots.empty()) {
    auto picked = resolve_record_robots(options.robots, names);
    if (!picked) return kernel::Error{picked.error()};
    setup.robots = std::move(picked).value();
  }
  const RecordFormat format = dir.empty() ? RecordFormat::kNone : resolve_record_format(options.format, n);
  RecordFigures& fig = r->figures_;
  fig.format = std::string(record_format_name(format));
  fig.recorded_robots = setup.robots ? setup.robots->size() : n;
  fig.crowd = n > kCrowdRobots;
  if (dir.empty()) {
    setup.paths = std::vector<std::size_t>{};  // no pictures: keep no paths
  } else if (fig.crowd) {
    setup.paths = sample_robots(n, kTrailSample, seed);
    setup.density = true;
  }
  if (writes_csv(format)) {
    r->csv_.open(dir / "steps.csv", std::ios::binary);
    if (!r->csv_) return kernel::Error{"cannot write " + (dir / "steps.csv").string()};
    setup.csv = &r->csv_;
  }
  if (writes_hdf5(format)) {
    StepsH5Meta meta;
    meta.scenario = scenario.name;
    meta.scenario_file = scenario.file;
    meta.seed = seed;
    meta.control_period_s = r->dt_;
    meta.record_every = setup.every;
    meta.robot_count = n;
    for (std::size_t i = 0; i < n; ++i)
      if (!setup.robots || std::binary_search(setup.robots->begin(), setup.robots->end(), i)) {
        meta.robots.push_back(names[i]);
        meta.robot_indices.push_back(i);
      }
    auto h5 = StepsH5::create(dir / "steps.h5", meta);
    if (!h5) return kernel::Error{h5.error()};
    r->h5_ = std::move(h5).value();
    setup.h5 = r->h5_.get();
  }
  r->recorder_ = std::make_unique<RunRecorder>(world, std::move(setup), r->dt_);
  return r;
}

kernel::Result<std::vector<fs::path>> RunRecording::finish(const sim::WorldSpec& world, std::string_view caption,
                                                           double simulated_seconds, bool interrupted) {
  const auto started = std::chrono::steady_clock::now();
  std::vector<fs::path> files;
  std::vector<fs::path> steps;
  RecordFigures& fig = figures_;
  fig.recorded_steps = recorder_->recorded_steps();
  fig.step_seconds = recorder_->seconds_spent();
  if (csv_.is_open()) {
    csv_.close();
    if (!csv_) return kernel::Error{"cannot write " + (dir_ / "steps.csv").string()};
    steps.push_back(dir_ / "steps.csv");
  }
  if (h5_) {
    if (auto st = h5_->close(simulated_seconds, interrupted); !st) return kernel::Error{st.error()};
    h5_.reset();
    steps.push_back(dir_ / "steps.h5");
  }
  if (!dir_.empty()) {
    const RunRecorder& rec = *recorder_;
    std::vector<std::pair<std::string, std::string>> pictures;
    if (!fig.crowd) {
      std::ostringstream svg;
      write_maze_svg(svg, world, rec.paths(), caption);
      pictures.emplace_back("trajectory.svg", svg.str());
    } else {
      const auto& robots = rec.summaries();
      std::ostringstream density, trails, stats;
      write_density_svg(density, world, *rec.density(), dt_,
                        std::string(caption) + ": where " + std::to_string(robots.size()) + " robots spent their time");
      std::vector<PathPoint> ends;
      for (const RobotSummary& s : robots) ends.push_back({s.end.x, s.end.y});
      write_maze_svg(trails, world, rec.paths(),
                     std::string(caption) + ": trails of " + std::to_string(rec.paths().size()) + " of " +
                         std::to_string(robots.size()) + " robots (sampled by seed " + std::to_string(seed_) +
                         "), grey: every robot's end",
                     ends);
      write_robot_stats_svg(stats, robots, simulated_seconds, caption);
      pictures.emplace_back("density.svg", density.str());
      pictures.emplace_back("trails.svg", trails.str());
      pictures.emplace_back("robot_stats.csv", robot_stats_csv(robots, simulated_seconds));
      pictures.emplace_back("robot_stats.svg", stats.str());
    }
    for (const auto& [name, text] : pictures) {
      if (auto st = write_file(dir_ / name, text); !st) return kernel::Error{st.error()};
      files.push_back(dir_ / name);
    }
  }
  fig.bytes = recorder_->csv_bytes();
  std::error_code ec;
  if (fs::exists(dir_ / "steps.h5", ec) && !steps.empty() && steps.back().filename() == "steps.h5")
    fig.bytes += fs::file_size(dir_ / "steps.h5", ec);
  files.insert(files.end(), steps.begin(), steps.end());
  fig.finish_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return files;
}

}  // namespace symb::apps::run
