// ControllerSwap: the part of an on-board evolution task that is the same whatever the algorithm
// (issue 7, paper IV-B): it swaps whole controller TASKS per candidate and times the candidate's
// evaluation from the fitness task's messages. The evolution task owns one and asks it to
//
//   set_up   find the sensor, actuator and fitness tasks by name and hook fitness -> evolution;
//   swap     remove the running controller (or, the first time, a task already bearing the
//            controller's name: a scenario's own controller) and create a new task of the
//            controller type with the candidate genome as its `weights`, hooked
//            sensor -> controller -> actuator and controller -> fitness;
//   feed     every fitness message [sum, steps, step] (or [sum, steps, window sum, N] for a report
//            of N steps): the steps inside `recovery` after the swap are not counted, the counted
//            ones are added, and once `recovery + evaluation` has passed the candidate's fitness
//            (the MEAN counted step value) is returned.
//
// The clock is the fitness messages' arrival time: no sensor data, no progress. Non-finite steps
// are skipped. Used by mu_plus_one_task (and open to any other algorithm of the evo layer).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "symb/evo/genome/real_genome.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"
#include "symb/os/ids.hpp"
#include "symb/os/message.hpp"
#include "symb/os/param.hpp"

namespace symb::os {
class Node;
}

namespace symb::evo {

struct ControllerSwapOptions {
  kernel::Duration evaluation = std::chrono::seconds(10);
  kernel::Duration recovery = std::chrono::seconds(1);
  // The candidate controllers: task type, name and the parameters besides `weights`.
  std::string controller_type = "mlp";
  std::string controller = "controller";
  std::string controller_params = "inputs=7 layers=2 activation=tanh";
  std::string sensor = "ir", actuator = "wheels", fitness = "fitness";
};

// Positive evaluation, recovery >= 0, valid task names, parseable controller parameters without
// `weights`. `who` prefixes the messages ("mu_plus_one: ...").
kernel::Status check(const ControllerSwapOptions& o, const std::string& who);

// The genome size of an mlp with these parameters (as the mlp task type takes them: input count,
// layer sizes "h1 h2 .. out", activation name): what `genes` must equal.
kernel::Result<std::size_t> mlp_genome_size(std::int64_t inputs, const std::string& layers,
                                            const std::string& activation);
// `genes` is that genome size; the message says both when it is not.
kernel::Status check_mlp_genes(std::size_t genes, std::int64_t inputs, const std::string& layers,
                               const std::string& activation);
// The candidate mlp's parameters besides `weights` (ControllerSwapOptions::controller_params).
std::string mlp_params_text(std::int64_t inputs, const std::string& layers, const std::string& activation);

class ControllerSwap {
 public:
  ControllerSwap(ControllerSwapOptions options, std::string who);

  // true: all three tasks found and fitness hooked to `evolution`; false: one is missing (retry
  // later); an error: the hook failed.
  kernel::Result<bool> set_up(os::Node& node, os::TaskId evolution);
  // Replaces the controller by one running `genome`, starting a new evaluation at `now`.
  kernel::Status swap(os::Node& node, const RealGenome& genome, kernel::Time now);
  // A message from the fitness task; the candidate's fitness once its evaluation is over.
  std::optional<double> feed(const os::Message& m, kernel::Time now);

  bool has_controller() const { return have_controller_; }
  os::TaskId fitness() const { return fitness_; }
  std::uint64_t counted_steps() const { return counted_steps_; }
  const ControllerSwapOptions& options() const { return options_; }

 private:
  ControllerSwapOptions options_;
  std::string who_;
  std::vector<os::ParamAssignment> params_;
  os::TaskId sensor_, actuator_, fitness_, controller_;
  bool have_controller_ = false;
  kernel::Time started_{0};
  double counted_sum_ = 0;
  std::uint64_t counted_steps_ = 0;
  double last_sum_ = 0;  // for [sum, steps] messages without the step
};

}  // namespace symb::evo
