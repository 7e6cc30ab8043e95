// OnePlusOneTask: (1+1)-ONLINE evolution running on the robot's own node (issue 7, paper IV-B:
// "evolution ... on-board and on-line"). It drives the pure algorithm (one_plus_one.hpp) with real
// time and real fitness, and it swaps whole controller TASKS, not weights: for each candidate it
// removes the running controller and creates a new task of type `mlp` through the node's task
// registry, with the candidate genome as its `weights`, then hooks it in:
//
//   ir --> controller(candidate k) --> wheels          (sensor, actuator: named by parameters)
//                                  --> fitness --[sum, steps, step]--> OnePlusOneTask
//
// A task named like the controller that is already on the node when evolution starts (a scenario's
// own controller) is replaced by the first candidate. The fitness task (type `fitness`, hooked from
// the sensor by whoever built the node) is only read: other algorithms may read it too.
//
// Timing of one evaluation, from the candidate's creation: `recovery` (default 1 s) during which
// fitness steps are not counted (the candidate first has to get out of wherever its predecessor
// left the robot), then `evaluation` (default 10 s) of counted steps. Its fitness is the MEAN step
// value over the counted steps (the reference's sum over a fixed number of steps, divided by that
// number: comparable whatever the step count). The clock is the fitness messages' arrival: no
// sensor data, no progress.
//
// Parameters (make time): evaluation, recovery, genes (must equal the mlp's genome size:
// (inputs + 1) x outputs for a perceptron, 16 for 7-2), inputs, layers, activation (the mlp's),
// lo, hi, sigma, sigma_min, sigma_max, reevaluation, controller, sensor, actuator, fitness (task
// names). The random numbers come from the task's own stream (Task::random()).
// Probes after every evaluation: "champion_fitness", "sigma", "evaluations", and "fitness" (the
// candidate's measured fitness, its kind: 0 first, 1 challenger, 2 re-evaluation); "champion" (the
// champion's genes as floats) after the evaluation that made a new champion; "immigrants"
// [migrants drawn as challengers, of them those that became champion] after a challenger once
// migrants came.
// If a task it needs is missing it logs a warning and retries every tick (period 1 s); if a
// controller cannot be created it logs the error and stops evolving (state kFailed). Removing
// the evolution task leaves the candidate of the moment driving.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "symb/evo/controller_swap.hpp"
#include "symb/evo/one_plus_one/one_plus_one.hpp"
#include "symb/kernel/time.hpp"
#include "symb/os/ids.hpp"
#include "symb/os/task.hpp"

namespace symb::evo {

struct OnePlusOneTaskOptions {
  OnePlusOneOptions algorithm;
  ControllerSwapOptions swap;
};

enum class EvolutionState : std::uint8_t { kWaiting, kRunning, kFailed };

// One finished evaluation.
struct EvaluationRecord {
  kernel::Time time{0};  // when it ended
  Candidate kind = Candidate::kFirst;
  double fitness = 0;
  double champion_fitness = 0;  // the stored fitness after the report
  double sigma = 0;             // the champion's step size after the report
  std::uint64_t steps = 0;      // counted fitness steps
};

// A migrant genome for the island model (apps/evolve/islands.hpp): a message on this port whose
// numbers are the genes (as many as the task's `genes`) becomes the next challenger
// (OnePlusOne::immigrate). Messages on it with another count are ignored with a warning.
inline constexpr os::Port kImmigrantPort = 60;

class OnePlusOneTask : public os::Task {
 public:
  static kernel::Result<std::unique_ptr<OnePlusOneTask>> create(OnePlusOneTaskOptions options);

  // Safe from any thread.
  EvolutionState state() const;
  std::string error() const;
  std::optional<RealGenome> champion() const;  // none before the first evaluation ended
  double champion_fitness() const;
  OnePlusOneCounts counts() const;
  std::vector<EvaluationRecord> history() const;
  std::uint64_t controllers_created() const;

 protected:
  void on_start() override;
  void on_tick() override;
  void on_message(const os::Message& m) override;

 private:
  static constexpr std::size_t kHistoryLimit = 1 << 16;  // evaluations kept for history() (days of driving)

  explicit OnePlusOneTask(OnePlusOneTaskOptions options);
  bool set_up();
  void start_candidate();
  void finish_evaluation(double fitness);
  void fail(const std::string& why);

  OnePlusOneTaskOptions options_;
  ControllerSwap swap_;
  std::optional<OnePlusOne> algorithm_;
  bool warned_missing_ = false;

  mutable std::mutex mu_;  // what the getters read
  EvolutionState state_ = EvolutionState::kWaiting;
  std::string error_;
  std::optional<RealGenome> champion_;
  double champion_fitness_ = 0;
  OnePlusOneCounts counts_;
  std::vector<EvaluationRecord> history_;
  std::uint64_t created_ = 0;
};

}  // namespace symb::evo
