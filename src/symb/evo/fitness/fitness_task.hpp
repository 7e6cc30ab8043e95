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
//    exact window of its own without subtracting two large floats). With `every` = N > 1, after
//    every N-th step instead: [sum, steps, window sum, N], the last N steps' sum and count: an
//    evolution task's windows then start and end on a report (at most N - 1 steps late), for a
//    fifth of the messages at N = 5 (each delivery costs as much as a tenth of a control step).
//  - Probe "fitness": [sum, steps, step] after every step.
//  - Runtime parameters: formula (takes effect from the next step), reset (true zeroes the sum
//    and the step count), command_timeout, every (from the next report on).
#pragma once

#include <atomic>
#include <cstdint>
#include <mutex>

#include "symb/evo/fitness/fitness.hpp"
#include "symb/kernel/counter.hpp"
#include "symb/kernel/time.hpp"
#include "symb/os/port_layout.hpp"
#include "symb/os/task.hpp"

namespace symb::evo {

// What the fitness task sends on port 0 ([sum, steps, step], or [sum, steps, window sum, N] with
// `every`), declared on its type so that a hook carrying it into wheels is refused.
inline constexpr os::PortLayout kFitnessReport{"fitness-report", "[sum, steps, step] or [sum, steps, window sum, N]"};

struct FitnessTaskOptions {
  FitnessFormula formula = FitnessFormula::kOnePlusOne;
  kernel::Duration command_timeout = std::chrono::milliseconds(100);
  std::uint32_t every = 1;  // report after every N-th step (1..1000)
  // Set true at runtime: zeroes the sum and the step count (then reads false again).
  bool reset = false;
};

struct FitnessStats {
  double sum = 0;
  std::uint64_t steps = 0;
  std::uint64_t commands = 0;  // wheel commands received
  std::uint64_t ignored = 0;   // messages neither a command nor a reading
};

class FitnessTask : public os::Task {
 public:
  explicit FitnessTask(FitnessTaskOptions options) : options_(options) { bind_parameters(options_); }

  // Safe from any thread.
  FitnessStats stats() const;
  // sum / steps, 0 before the first step.
  double mean() const;

 protected:
  void on_message(const os::Message& m) override;
  kernel::Status on_parameter_changed(std::string_view name) override;

 private:
  FitnessTaskOptions options_;
  float left_ = 0, right_ = 0;
  kernel::Time command_time_{0};
  bool have_command_ = false;
  double window_sum_ = 0;  // steps since the last report
  std::uint32_t window_steps_ = 0;

  // Written by the task's own context only, read by stats() from anywhere: atomics, not a lock
  // (two per control step otherwise).
  std::atomic<double> sum_{0};
  kernel::Counter steps_, commands_, ignored_;
};

}  // namespace symb::evo
