// RunRecorder: what a run keeps for the person afterwards, gathered once per world step on the
// stepping context: robots' paths and contacts (for the pictures), every robot's summary figures,
// the recorded steps (a CSV row per recorded robot and step, and/or an HDF5 row), a crowd's
// density grid, and a hash of every pose and wheel speed (equal hashes, equal runs). Used by
// `symb run` and by the simulator side of `symb sim`.
#pragma once

#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "symb/apps/run/crowd_pictures.hpp"
#include "symb/apps/run/maze_svg.hpp"
#include "symb/sim/world.hpp"
#include "symb/sim/world_runner.hpp"

namespace symb::apps::run {

class StepsH5;

struct RobotSummary {
  std::string name;
  double distance = 0;               // cm
  std::uint64_t contact_steps = 0;   // steps in contact with a wall or a robot
  std::uint64_t contact_events = 0;  // contacts begun
  double moving_seconds = 0;         // time with a wheel speed above 1 cm/s
  sim::Pose end;
};

// Where the recorded steps go and which; what the pictures need.
struct RecorderSetup {
  std::ostream* csv = nullptr;  // steps.csv rows; null: none (the header is written at once)
  StepsH5* h5 = nullptr;        // steps.h5 rows; null: none
  std::uint32_t every = 1;      // rows for every `every`-th step (the first step is kept)
  // The robots whose rows are recorded, in the world's order; none: every robot.
  std::optional<std::vector<std::size_t>> robots;
  // The robots whose paths are kept for a picture; none: every robot.
  std::optional<std::vector<std::size_t>> paths;
  bool density = false;  // gather density() (a crowd's density.svg)
};

class RunRecorder {
 public:
  // `csv` may be null (no rows); rows for every `csv_every`-th step; `dt` is the step in seconds.
  // The header row is written at once. Every robot's path is kept.
  RunRecorder(const sim::World& world, std::ostream* csv, std::uint32_t csv_every, double dt);
  RunRecorder(const sim::World& world, RecorderSetup setup, double dt);

  // After each world step (a WorldRunner observer).
  void on_step(const sim::StepRecord& record);

  std::uint64_t steps() const { return steps_; }
  std::uint64_t recorded_steps() const { return recorded_; }
  std::uint64_t hash() const { return hash_; }
  const std::vector<RobotSummary>& summaries() const { return summaries_; }
  // The kept paths (RecorderSetup::paths, in that order).
  const std::vector<RobotPath>& paths() const { return paths_; }
  // Null unless RecorderSetup::density.
  const DensityGrid* density() const { return density_ ? &*density_ : nullptr; }
  // Bytes of CSV text written so far, and wall-clock seconds spent in on_step.
  std::uint64_t csv_bytes() const { return csv_bytes_; }
  double seconds_spent() const { return seconds_spent_; }

 private:
  void mix(std::uint64_t word);

  RecorderSetup setup_;
  double dt_;
  std::uint64_t steps_ = 0;
  std::uint64_t recorded_ = 0;
  std::uint64_t hash_ = 0xcbf29ce484222325ULL;  // FNV-1a offset basis
  std::vector<RobotSummary> summaries_;
  std::vector<bool> was_in_contact_;
  std::vector<std::size_t> row_robots_;  // whose rows
  std::vector<std::size_t> path_of_;     // robot -> index in paths_, or npos
  std::vector<RobotPath> paths_;
  bool crowd_paths_ = false;  // thin the paths (more than 10 of them)
  std::optional<DensityGrid> density_;
  std::string row_text_;  // one step's CSV rows, written at once
  std::uint64_t csv_bytes_ = 0;
  double seconds_spent_ = 0;
};

}  // namespace symb::apps::run
