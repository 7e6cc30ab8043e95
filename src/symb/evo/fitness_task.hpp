// FitnessTask: on-line fitness as a task, hooked to the robot's sensor and to its controller
// (issue 7: "fitness measured by tasks hooked to its sensors"). Every algorithm on the node reads
// the same running sum, so a formula is computed once, in one place (fitness.hpp):
//
//   ir ---------port 0: 7 IR readings---------->  FitnessTask --port 0: [sum, steps, step]--> readers
//   controller --port 0: [left, right] command-->
//
// Contract:
//  - In, port 0 only, classified by length: 2 numbers = a wheel command [left, right] in motor
//    units (kept as the latest command); 3 or more = an IR reading. Anything else (1 number, a
//    blob, another port) is counted as ignored.
//  - On every IR reading the task adds one step of its formula, computed with the latest wheel
//    command: the command the wheels drove with since the previous reading. A command older than
//    `command_timeout` counts as [0, 0] (the wheels' watchdog has stopped the robot by then), and
//    so does the time before the first command.
//  - Out, port 0, after every step: [sum, steps, step]: the running sum since the start (or the
//    last reset), the number of steps summed, and the step just added (so a reader can add up an
//    exact window of its own without subtracting two large floats).
//  - Probe "fitness": [sum, steps, step] after every step.
//  - Runtime parameters: formula (takes effect from the next step), reset (true zeroes the sum
//    and the step count), command_timeout.
#pragma once

#include <cstdint>
#include <mutex>

#include "symb/evo/fitness.hpp"
#include "symb/kernel/time.hpp"
#include "symb/os/task.hpp"

namespace symb::evo {

struct FitnessTaskOptions {
  FitnessFormula formula = FitnessFormula::kOnePlusOne;
  kernel::Duration command_timeout = std::chrono::milliseconds(100);
};

struct FitnessStats {
  double sum = 0;
  std::uint64_t steps = 0;
  std::uint64_t commands = 0;  // wheel commands received
  std::uint64_t ignored = 0;   // messages neither a command nor a reading
};

class FitnessTask : public os::Task {
 public:
  explicit FitnessTask(FitnessTaskOptions options) : options_(options) {}

  // Safe from any thread.
  FitnessStats stats() const;
  // sum / steps, 0 before the first step.
  double mean() const;

 protected:
  void on_message(const os::Message& m) override;
  kernel::Status on_parameter(std::string_view name, const os::ParamValue& value) override;

 private:
  FitnessTaskOptions options_;
  float left_ = 0, right_ = 0;
  kernel::Time command_time_{0};
  bool have_command_ = false;

  mutable std::mutex mu_;
  FitnessStats stats_;
};

}  // namespace symb::evo
