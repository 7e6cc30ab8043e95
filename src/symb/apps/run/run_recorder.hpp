// RunRecorder: what a run keeps for the person afterwards, gathered once per world step on the
// stepping context: every robot's path and contacts (for the picture), its summary figures, a
// CSV row per robot and recorded step, and a hash of every pose and wheel speed (equal hashes,
// equal runs). Used by `symb run` and by the simulator side of `symb sim`.
#pragma once

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "symb/apps/run/maze_svg.hpp"
#include "symb/sim/world.hpp"
#include "symb/sim/world_runner.hpp"

namespace symb::apps::run {

struct RobotSummary {
  std::string name;
  double distance = 0;               // cm
  std::uint64_t contact_steps = 0;   // steps in contact with a wall or a robot
  std::uint64_t contact_events = 0;  // contacts begun
  double moving_seconds = 0;         // time with a wheel speed above 1 cm/s
  sim::Pose end;
};

class RunRecorder {
 public:
  // `csv` may be null (no rows); rows for every `csv_every`-th step; `dt` is the step in seconds.
  // The header row is written at once.
  RunRecorder(const sim::World& world, std::ostream* csv, std::uint32_t csv_every, double dt);

  // After each world step (a WorldRunner observer).
  void on_step(const sim::StepRecord& record);

  std::uint64_t steps() const { return steps_; }
  std::uint64_t hash() const { return hash_; }
  const std::vector<RobotSummary>& summaries() const { return summaries_; }
  const std::vector<RobotPath>& paths() const { return paths_; }

 private:
  void mix(std::uint64_t word);

  std::ostream* csv_;
  std::uint32_t csv_every_;
  double dt_;
  std::uint64_t steps_ = 0;
  std::uint64_t hash_ = 0xcbf29ce484222325ULL;  // FNV-1a offset basis
  std::vector<RobotPath> paths_;
  std::vector<RobotSummary> summaries_;
  std::vector<bool> was_in_contact_;
};

}  // namespace symb::apps::run
