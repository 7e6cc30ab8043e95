// The loop of an in-process run (`symb run`, 2D or 3D): the executor runs the session in slices,
// with a progress report per slice, pacing to the wall clock when asked (--speed), and a stop
// between slices when asked (Ctrl-C) or when the session failed. The session is started before
// and stopped after by the caller; only time passes here.
#pragma once

#include <chrono>
#include <functional>

#include "symb/apps/run/run_control.hpp"
#include "symb/apps/run/scenario_run.hpp"
#include "symb/kernel/lockstep_executor.hpp"
#include "symb/kernel/time.hpp"
#include "symb/kernel/virtual_time_executor.hpp"

namespace symb::apps::run {

struct RunLoop {
  // Both null: the session runs on OS threads against the wall clock, and the loop only waits.
  // Otherwise one of them runs the session in virtual time (a 2D run is lockstep, a 3D one not).
  kernel::VirtualTimeExecutor* virtual_time = nullptr;
  kernel::LockstepExecutor* lockstep = nullptr;
  kernel::Duration duration{};
  double speed = 0;  // virtual time only: 0 as fast as possible, else simulated / wall seconds
  std::chrono::steady_clock::time_point wall_start;
  std::function<void(const RunProgress&)> on_progress;  // may be empty
  std::function<bool()> stop_requested;                 // may be empty
  std::function<bool()> failed;                         // polled after each slice; may be empty
  // Virtual time: pause, step and speed asked for while it runs (then `speed` above is only
  // where it starts; the control's speed rules). May be null.
  RunControl* control = nullptr;
  // Called on the run's thread after each slice and while it waits (pacing, paused): between
  // slices no robot's node runs, so a node may be read here (the web view). May be empty.
  std::function<void()> between_slices;
};

// Runs until the duration is over, a stop is requested or the session failed; true when a stop
// was requested (the run is then interrupted).
bool run_slices(const RunLoop& loop);

}  // namespace symb::apps::run
