// RunRecording: the files a 2D `symb run` records as it goes and the pictures it draws at the end,
// as RecordOptions ask: steps.csv and/or steps.h5 (every N-th step, the chosen robots), and
// either trajectory.svg (a path per robot) or, for a crowd (more than kCrowdRobots robots),
// density.svg, trails.svg, robot_stats.csv and robot_stats.svg (crowd_pictures.hpp). It owns the
// step files and the RunRecorder that fills them; the run hands the recorder every step.
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "symb/apps/run/record_options.hpp"
#include "symb/apps/run/run_recorder.hpp"
#include "symb/apps/run/steps_h5.hpp"
#include "symb/kernel/result.hpp"
#include "symb/sim/scenario.hpp"

namespace symb::apps::run {

// What recording cost, for summary.txt and the measurements in docs/run.md.
struct RecordFigures {
  std::string format;                // "csv", "hdf5", "both" or "none" (auto resolved)
  std::uint64_t recorded_steps = 0;  // steps with rows
  std::size_t recorded_robots = 0;   // robots with rows
  std::uint64_t bytes = 0;           // of steps.csv and steps.h5
  double step_seconds = 0;           // wall clock in the recorder during the run
  double finish_seconds = 0;         // closing the step files and drawing the pictures
  bool crowd = false;                // crowd pictures instead of trajectory.svg
};

class RunRecording {
 public:
  // Resolves the options against `world` (a bad --record-robots item is an error naming it) and
  // opens the step files in `dir`; an empty `dir` writes nothing (the recorder then only keeps
  // the summaries and the hash). `every` >= 1.
  static kernel::Result<std::unique_ptr<RunRecording>> open(const sim::World& world, const sim::Scenario& scenario,
                                                            std::uint64_t seed, const RecordOptions& options,
                                                            std::uint32_t every, const std::filesystem::path& dir);

  RunRecorder& recorder() { return *recorder_; }
  const RunRecorder& recorder() const { return *recorder_; }

  // Closes the step files (steps.h5 gets simulated_s and interrupted) and draws the pictures,
  // each captioned `caption`. Returns the files written: pictures first, then the step files.
  kernel::Result<std::vector<std::filesystem::path>> finish(const sim::WorldSpec& world, std::string_view caption,
                                                            double simulated_seconds, bool interrupted);
  const RecordFigures& figures() const { return figures_; }

 private:
  RunRecording() = default;

  std::filesystem::path dir_;
  std::uint64_t seed_ = 0;
  double dt_ = 0;
  std::ofstream csv_;
  std::unique_ptr<StepsH5> h5_;
  std::unique_ptr<RunRecorder> recorder_;
  RecordFigures figures_;
};

}  // namespace symb::apps::run
