// MuPlusOneTask: encapsulated (mu+1)-ONLINE evolution running on the robot's own node (issue 7;
// Haasdijk, Eiben, Karafotias, CEC 2010). It drives the pure algorithm (mu_plus_one.hpp) with
// real time and real fitness and, like one_plus_one, swaps whole controller TASKS per candidate
// (controller_swap.hpp does the swapping and the timing):
//
//   ir --> controller(candidate k) --> wheels          (sensor, actuator: named by parameters)
//                                  --> fitness --[sum, steps, step]--> MuPlusOneTask
//
// Timing of one evaluation, from the candidate's creation: `recovery` (default 1 s) not counted,
// then `evaluation` (tau, default 10 s) of counted steps; its fitness is the MEAN counted step.
// The fitness task (type `fitness`) is only read.
//
// Parameters (make time): mu, rho, sigma, crossover, selection (tournament | uniform),
// reevaluation (average | replace), evaluation, recovery, genes (= the mlp's genome size),
// inputs, layers, activation, lo, hi, controller, sensor, actuator, fitness (task names).
// Random numbers from the task's own stream (Task::random()).
// Probes after every evaluation: "fitness" [measured, kind: 0 initial, 1 child, 2 re-evaluation],
// "best_fitness", "mean_fitness", "evaluations", and "champion" (the best member's genes) when
// another genome becomes the best; "immigrants" [migrants evaluated or drawn, of them those that
// replaced the worst member] after a child once migrants came. A migrant for the island model
// arrives on kImmigrantPort (as for one_plus_one: its numbers are the genes) and becomes the next
// candidate once the population is full (MuPlusOne::immigrate).
// A missing task: a warning, then a retry every tick (period 1 s); a controller that cannot be
// created: the error is logged and evolution stops (state kFailed). Removing the evolution task
// leaves the candidate of the moment driving.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "symb/evo/controller_swap.hpp"
#include "symb/evo/mu_plus_one/mu_plus_one.hpp"
#include "symb/evo/one_plus_one/one_plus_one_task.hpp"  // EvolutionState
#include "symb/kernel/time.hpp"
#include "symb/os/task.hpp"
#include "symb/os/task_type_registry.hpp"

namespace symb::evo {

struct MuPlusOneTaskOptions {
  MuPlusOneOptions algorithm;
  ControllerSwapOptions swap;
};

// One finished evaluation.
struct MuEvaluationRecord {
  kernel::Time time{0};  // when it ended
  MuCandidate kind = MuCandidate::kInitial;
  double fitness = 0;
  double best_fitness = 0;  // the population's best stored fitness after the report
  double mean_fitness = 0;  // its mean
  std::uint64_t steps = 0;  // counted fitness steps
};

class MuPlusOneTask : public os::Task {
 public:
  static kernel::Result<std::unique_ptr<MuPlusOneTask>> create(MuPlusOneTaskOptions options);

  // Safe from any thread.
  EvolutionState state() const;
  std::string error() const;
  std::optional<Member> best() const;  // none before the first evaluation ended
  std::vector<Member> population() const;
  MuPlusOneCounts counts() const;
  std::vector<MuEvaluationRecord> history() const;
  std::uint64_t controllers_created() const;

 protected:
  void on_start() override;
  void on_tick() override;
  void on_message(const os::Message& m) override;

 private:
  static constexpr std::size_t kHistoryLimit = 1 << 16;  // evaluations kept for history() (days of driving)

  explicit MuPlusOneTask(MuPlusOneTaskOptions options)
      : options_(std::move(options)), swap_(options_.swap, "mu_plus_one") {}
  bool set_up();
  void start_candidate();
  void finish_evaluation(double fitness);
  void fail(const std::string& why);

  MuPlusOneTaskOptions options_;
  ControllerSwap swap_;
  std::optional<MuPlusOne> algorithm_;
  bool warned_missing_ = false;
  std::vector<double> probed_best_;  // the genes of the last "champion" probe

  mutable std::mutex mu_;  // what the getters read
  EvolutionState state_ = EvolutionState::kWaiting;
  std::string error_;
  std::vector<Member> population_;
  std::optional<Member> best_;
  MuPlusOneCounts counts_;
  std::vector<MuEvaluationRecord> history_;
  std::uint64_t created_ = 0;
};

// Adds the type `mu_plus_one` (defaults: priority 1, period 1 s, queue 8). Called by
// register_evo_task_types.
kernel::Status register_mu_plus_one_task_types(os::TaskTypeRegistry& registry);

}  // namespace symb::evo
