// RunControl: pause, single steps and speed of a virtual-time run, asked for from another thread
// (the web view's page) and obeyed by the run loop (run_loop.hpp) between two slices. A step runs
// `step_length` of simulated time (the control period) while paused. Speed 0 runs as fast as
// possible; s > 0 keeps simulated time at s times the wall clock from the moment it was set.
#pragma once

#include <atomic>
#include <cstdint>

#include "symb/kernel/time.hpp"

namespace symb::apps::run {

class RunControl {
 public:
  explicit RunControl(double speed, kernel::Duration step_length) : speed_(speed), step_length_(step_length) {}

  void pause() { paused_.store(true); }
  void resume() { paused_.store(false); }
  // While paused: one more step to run (they add up); running: nothing.
  void step() {
    if (paused_.load()) steps_.fetch_add(1);
  }
  // s >= 0 (0: as fast as possible); a negative value is taken as 0.
  void set_speed(double s) { speed_.store(s > 0 ? s : 0); }

  bool paused() const { return paused_.load(); }
  double speed() const { return speed_.load(); }
  kernel::Duration step_length() const { return step_length_; }

  // The run loop's side: a step asked for and not yet run, taken.
  bool take_step() {
    for (std::uint32_t n = steps_.load(); n > 0;)
      if (steps_.compare_exchange_weak(n, n - 1)) return true;
    return false;
  }

 private:
  std::atomic<bool> paused_{false};
  std::atomic<std::uint32_t> steps_{0};
  std::atomic<double> speed_;
  const kernel::Duration step_length_;
};

}  // namespace symb::apps::run
