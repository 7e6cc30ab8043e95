// ArbiterTask: several controller variants run side by side on one robot (paper section VI-C,
// "run several variants of a controller ... and evaluate the performance on the spot"); each
// sends its wheel commands to the arbiter instead of the wheels, and the arbiter forwards the
// commands of the one that currently scores best.
//
//   ir --+--> variant A --+
//        +--> variant B --+--> arbiter --port 0--> wheels
//        +--> variant C --+      ^
//        +-----------------------+  (the readings too)
//
// The score, and why: only the driving variant's commands move the robot, so a realised fitness
// (the Floreano-Mondada formula on what happened) exists for one variant only. Every variant,
// though, answers every reading, so the arbiter scores each one's OWN command against the reading
// it answers: a predicted step fitness (predicted_step_fitness below). Away from walls it is the
// Floreano-Mondada speed term V (1 - sqrt(dv)); near a wall (proximity d, the highest front IR
// scaled to 0..1) it blends, by d, into "turns away from the nearer side and does not advance":
//   score = (1 - d) V (1 - sqrt(dv)) + d (away - forward)
// Each variant's score is averaged over a sliding exponential window (time constant `window`),
// each step weighted by open_weight + d: in open space every sane variant drives straight on and
// they all score alike, so the moments near walls, where they differ, must dominate.
// Switching has hysteresis: a challenger takes over only when its average beats the driver's by
// `margin` and the last switch is `dwell` ago. A variant that has sent nothing for `stale`
// (removed, suspended or silent) is forgotten; when it was driving, the best other one takes over
// at once.
//
// Contract:
//  - In, port 0: a message of 3 or more finite numbers is an IR reading (7 for the Thymio: far
//    left, left, centre, right, far right, back left, back right); one of exactly 2 is a wheel
//    command [left, right] of the variant that sent it (Message::source). Anything else (other
//    ports, blobs, non-finite numbers) is counted and ignored; a non-finite command scores -1.
//  - Out, port 0: the driving variant's commands, each clamped to +-speed_max, as they arrive.
//  - Probes: "arbiter/active" [index of the driver among the variants heard so far, -1 for none],
//    "arbiter/scores" [average per variant, in the same order] once per reading.
#pragma once

#include <cstdint>
#include <mutex>
#include <optional>
#include <span>
#include <vector>

#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"
#include "symb/os/ids.hpp"
#include "symb/os/task.hpp"
#include "symb/os/task_type_registry.hpp"

namespace symb::evo {

struct ArbiterOptions {
  double ir_max = 4500;    // an IR value that means touching
  double speed_max = 500;  // Thymio motor units
  kernel::Duration window = std::chrono::seconds(10);
  double margin = 0.1;
  kernel::Duration dwell = std::chrono::seconds(2);
  kernel::Duration stale = std::chrono::milliseconds(150);
  std::uint32_t min_samples = 20;  // a variant is a challenger only after this many scored commands
  double open_weight = 0.1;        // a step's weight in the average is open_weight + proximity
};

// The proximity in 0..1: the highest of the five front readings over ir_max.
double danger(std::span<const float> ir, const ArbiterOptions& options);

// The score in [-1, 1] of command [left, right] (motor units) answering `ir` (>= 5 readings).
double predicted_step_fitness(std::span<const float> ir, double left, double right, const ArbiterOptions& options);

struct ArbiterVariant {
  os::TaskId source;
  double average = 0;  // weighted_sum / weight_sum
  double weighted_sum = 0, weight_sum = 0;
  std::uint64_t samples = 0;
  kernel::Time last{0};
};

struct ArbiterStats {
  std::optional<os::TaskId> active;
  std::vector<ArbiterVariant> variants;  // in the order first heard
  std::uint64_t switches = 0;            // driver changes after the first pick
  std::uint64_t dropped = 0;             // variants forgotten for staleness
  std::uint64_t forwarded = 0, ignored = 0;
};

class ArbiterTask final : public os::Task {
 public:
  explicit ArbiterTask(ArbiterOptions options);
  // Safe from any thread.
  ArbiterStats stats() const;

 protected:
  void on_message(const os::Message& m) override;

 private:
  void on_reading(std::span<const float> ir);
  void on_command(os::TaskId source, float left, float right);
  void drop_stale();
  ArbiterVariant* variant(os::TaskId id);
  void switch_to(std::optional<os::TaskId> id);

  ArbiterOptions options_;
  std::vector<float> ir_;
  mutable std::mutex mu_;  // guards stats_ (read by stats() from other threads)
  ArbiterStats stats_;
  kernel::Time last_switch_{0};
};

// The `arbiter` task type (parameters: the options above).
os::TaskType arbiter_task_type();
kernel::Status register_arbiter_task_type(os::TaskTypeRegistry& registry);

}  // namespace symb::evo
