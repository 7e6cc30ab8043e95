// OscillatorTask: a PhaseOscillator (phase_oscillator.hpp) as a task, one per joint. Each module of
// a chain runs one on its own node and drives its own hinge; the oscillators couple only through
// the phases they send each other, so the coupling messages can travel over the organism bus
// between modules as well as between tasks of one node.
//
//   port 1 (in)  [id, phase]    a neighbour's phase (rad), stamped by its message's send time
//   port 0 (out) [angle]        the joint target, rad: offset + amplitude * sin(phase)
//   port 1 (out) [id, phase]    this oscillator's id and phase, for its neighbours
//
// It steps at every tick of its period (required) and sends both outputs; messages only update
// what it heard. A message that is not [id, phase] with finite numbers, or comes on another port,
// is counted in `ignored` (warned at most once per second); a phase from an id that is not a chain
// neighbour is counted in `foreign` and ignored, so one hook may carry every module's phase.
// Probe "oscillator": [phase, output, neighbours coupled].
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "symb/control/cpg/phase_oscillator.hpp"
#include "symb/kernel/counter.hpp"
#include "symb/kernel/time.hpp"
#include "symb/os/task.hpp"
#include "symb/os/warning_limiter.hpp"

namespace symb::control::cpg {

inline constexpr os::Port kJointTargetPort = 0;
inline constexpr os::Port kPhasePort = 1;

// The task's parameters (the task type declares them; durations as the node's time).
struct OscillatorOptions {
  std::int64_t id = 0;
  double frequency = 0.5;
  double amplitude = 0.5;
  double offset = 0;
  double coupling = 4.0;
  double lag = 1.5707963267948966;
  kernel::Duration neighbour_timeout = std::chrono::milliseconds(500);
  double initial_phase = 0;
  // Draw the initial phase uniformly from [0, 2 pi) with the task's own random stream instead: the
  // seed then decides where each oscillator of a chain starts (and the chain must still lock).
  bool random_phase = false;
};

struct OscillatorStats {
  std::uint64_t steps = 0;
  std::uint64_t heard = 0;    // neighbour phases taken
  std::uint64_t foreign = 0;  // phases of ids that are not neighbours
  std::uint64_t ignored = 0;  // malformed messages
};

class OscillatorTask : public os::Task {
 public:
  explicit OscillatorTask(OscillatorOptions options);
  OscillatorStats stats() const;
  // The oscillator's phase after the last step, rad. Any thread.
  double phase() const { return phase_.load(std::memory_order_relaxed); }

  static OscillatorParams params_of(const OscillatorOptions& options);

 protected:
  void on_start() override;
  void on_tick() override;
  void on_message(const os::Message& m) override;
  kernel::Status on_parameter_changed(std::string_view name) override;

 private:
  void ignore(const char* why);
  static double seconds(kernel::Time t);

  OscillatorOptions o_;
  PhaseOscillator oscillator_;
  std::atomic<double> phase_{0};
  os::WarningLimiter warning_;
  struct Counters {
    kernel::Counter steps, heard, foreign, ignored;
  } counters_;
};

}  // namespace symb::control::cpg
