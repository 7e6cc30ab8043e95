// PeriodicRunner: the life cycle a simulated world's runner has whatever its backend: an activity
// on the robots' executor (virtual-time or threads) that calls step_once() at its period, starts
// and stops at runtime, and stops itself, keeping the reason, when a step fails. The 3D runner
// (mujoco/mujoco_runner.hpp) derives from it; a backend says only what one tick does.
//
// Lifetime: the executor must outlive the runner. A derived class calls halt() first in its own
// destructor (before its members go, a tick under the thread executor may still be running).
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>

#include "symb/kernel/executor.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"

namespace symb::sim {

class PeriodicRunner : private kernel::Activity {
 public:
  struct Options {
    kernel::Duration period = std::chrono::milliseconds(30);  // 33.33 Hz, the paper's control rate
    int priority = 100;  // above the task types' defaults; a scenario session puts its world above any task
    std::string name = "world";
  };

  // Throws std::invalid_argument unless the period is in (0, 1 s].
  PeriodicRunner(kernel::Executor& executor, Options options);
  ~PeriodicRunner() override;
  PeriodicRunner(const PeriodicRunner&) = delete;
  PeriodicRunner& operator=(const PeriodicRunner&) = delete;

  // Attaches the runner to the executor: the first step comes one period later. Fails when it is
  // already running.
  kernel::Status start();
  // Detaches it. Under the thread executor, called from another thread, returns once the last
  // tick has finished; otherwise (from the runner's own tick, or under the virtual-time executor
  // inside a run) the last tick may still be under way. A stopped runner may start again.
  void stop();
  bool running() const;
  // Ticks that completed (step_once succeeded).
  std::uint64_t ticks() const { return ticks_.load(std::memory_order_acquire); }
  const Options& options() const { return options_; }
  // Why the runner stopped on its own (a step failed or threw), or empty.
  std::string error() const;

 protected:
  kernel::Executor& executor() const { return executor_; }
  // One tick at node time `now`. An error (or an exception) stops the runner, and error() keeps
  // "world runner '<name>' stopped: <the error>".
  virtual kernel::Status step_once(kernel::Time now) = 0;
  // Called once on the runner's context after a failed step, with the text error() now gives.
  virtual void on_failed(const std::string& /*error*/) {}
  // Stops the runner and waits until the executor has let go of it (see Lifetime above).
  void halt();

 private:
  void on_activity_attached(kernel::ActivitySlot& slot) override;
  void on_activity_start() override;
  void on_activity_input() override {}
  void on_activity_tick() override;
  void on_activity_stop() override {}
  void on_activity_released() override;
  void fail(const std::string& why);

  kernel::Executor& executor_;
  const Options options_;
  mutable std::mutex state_mu_;  // slot_, attached_, error_
  std::condition_variable released_cv_;
  kernel::ActivitySlot* slot_ = nullptr;
  bool attached_ = false;  // between attach and on_activity_released
  std::string error_;
  std::atomic<std::thread::id> runner_thread_{};
  std::atomic<std::uint64_t> ticks_{0};
};

}  // namespace symb::sim
