#include "symb/apps/run/run_loop.hpp"

#include <algorithm>
#include <thread>

namespace symb::apps::run {

namespace {

double loop_seconds(kernel::Duration d) { return std::chrono::duration<double>(d).count(); }

}  // namespace

bool run_slices(const RunLoop& loop) {
  const auto wall_seconds = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - loop.wall_start).count();
  };
  const double total = loop_seconds(loop.duration);
  const auto report = [&](double simulated) {
    if (loop.on_progress) loop.on_progress(RunProgress{simulated, total, wall_seconds()});
  };
  const auto failed = [&] { return loop.failed && loop.failed(); };
  bool stopped = false;
  const auto stop = [&] {
    if (!stopped && loop.stop_requested && loop.stop_requested()) stopped = true;
    return stopped;
  };
  kernel::VirtualTimeExecutor* virtual_time = loop.virtual_time;
  kernel::LockstepExecutor* lockstep = loop.lockstep;
  const auto virtual_now = [&] { return lockstep ? lockstep->now() : virtual_time->now(); };
  const auto run_until = [&](kernel::Time t) { lockstep ? lockstep->run_until(t) : virtual_time->run_until(t); };
  const auto wait_injected = [&](kernel::Duration timeout) {
    lockstep ? lockstep->wait_injected(timeout) : virtual_time->wait_injected(timeout);
  };
  if (virtual_time || lockstep) {
    // Slices: a progress report per slice; with a speed, the wall clock paces each slice and
    // shell commands (injected work) are served while waiting. With a control the speed may
    // change, and the run may stand still (paused) or go one step at a time.
    RunControl* control = loop.control;
    const auto speed_now = [&] { return control ? control->speed() : loop.speed; };
    const auto between = [&] {
      if (loop.between_slices) loop.between_slices();
    };
    const kernel::Time start = virtual_now();
    const kernel::Time end = start + loop.duration;
    // Pacing keeps simulated time since the anchor at speed times the wall clock since it; the
    // anchor moves when the speed changes and after a pause.
    auto anchor_wall = loop.wall_start;
    kernel::Time anchor_t = start;
    double paced_speed = speed_now();
    auto last_report = std::chrono::steady_clock::now();
    for (kernel::Time t = start; t < end && !stop();) {
      if (control && control->paused()) {
        if (control->take_step()) {
          t = std::min(end, t + control->step_length());
          run_until(t);
          report(loop_seconds(t - start));
        } else {
          wait_injected(std::chrono::milliseconds(20));
          run_until(t);  // what the injected work set off at this instant (a shell's reply)
        }
        between();
        if (failed()) break;
        anchor_wall = std::chrono::steady_clock::now();
        anchor_t = t;
        continue;
      }
      const double speed = speed_now();
      if (speed != paced_speed) {
        paced_speed = speed;
        anchor_wall = std::chrono::steady_clock::now();
        anchor_t = t;
      }
      // A control wants short slices at full speed too: a pause or a step is obeyed within one.
      const kernel::Duration slice = speed > 0 ? std::chrono::milliseconds(20)
                                     : control ? std::chrono::milliseconds(100)
                                               : std::chrono::milliseconds(1000);
      t = std::min(end, t + slice);
      run_until(t);
      between();
      if (failed()) break;
      if (speed > 0) {
        const auto due = anchor_wall + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                           std::chrono::duration<double>(loop_seconds(t - anchor_t) / speed));
        const auto changed = [&] { return control && (control->paused() || control->speed() != speed); };
        for (auto now = std::chrono::steady_clock::now(); now < due && !stop() && !changed();
             now = std::chrono::steady_clock::now()) {
          wait_injected(std::min<kernel::Duration>(due - now, std::chrono::milliseconds(20)));
          between();
        }
      }
      if (std::chrono::steady_clock::now() - last_report > std::chrono::milliseconds(100) || t == end) {
        report(loop_seconds(t - start));
        last_report = std::chrono::steady_clock::now();
      }
    }
  } else {
    for (double elapsed = wall_seconds(); elapsed < total && !stop(); elapsed = wall_seconds()) {
      std::this_thread::sleep_for(std::chrono::duration<double>(std::min(0.1, total - elapsed)));
      report(std::min(total, wall_seconds()));
      if (loop.between_slices) loop.between_slices();
      if (failed()) break;
    }
  }
  return stopped;
}

}  // namespace symb::apps::run
