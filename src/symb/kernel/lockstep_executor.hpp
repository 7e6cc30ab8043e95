// LockstepExecutor: the deterministic parallel executor. Virtual time, like the
// VirtualTimeExecutor, but a swarm's nodes run on both cores: each node runs on a lane of its own
// (lane(i), a VirtualTimeExecutor), and everything attached to the LockstepExecutor itself (the
// world runner, the radio, scenario events, observers) runs on its main lane. Lanes meet only
// through the main lane: a world step reads the wheels and publishes sensor readings into the
// lanes, the radio posts into them, an event runs a shell line on one of their nodes.
//
// A run goes from sync instant to sync instant. At a sync instant t every lane is idle:
//   (A) serially, on the calling thread, the main lane handles its events at t (the world steps,
//       publishes, the radio delivers; their posts into the lanes are made directly, the calling
//       thread standing in as each lane's own context: see VirtualTimeExecutor::set_host);
//   (B) in parallel on the worker pool, every lane handles its events in [t, t'), where t' is the
//       main lane's next event (at most t + quantum), and its clock is set to t'.
// So a cross-lane effect is always applied while the lanes are idle, in the main lane's own
// deterministic order, and a lane's events never depend on how the lanes were spread over the
// threads: a run is the same, bit for bit, with 1, 2 or 4 threads. With one thread it is also
// the VirtualTimeExecutor's run of the same nodes, as long as no lane event at an instant t has a
// higher priority than a main-lane event at t (a world step at t comes first here whatever the
// priorities; a scenario session's world runner is above every priority a task can have).
//
// Threads: run_*(), lane(), stop(), run_injected() and wait_injected() are for the thread that
// runs the executor (lane() outside phase B); inject() on the executor or on any lane may come
// from any thread, and is run at the next sync instant (a lane's at its next window).
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <vector>

#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/kernel/worker_pool.hpp"

namespace symb::kernel {

class LockstepExecutor final : public Executor {
 public:
  struct Options {
    unsigned threads = 1;  // worker threads, the caller's included
    // The longest window (B) when the main lane's next event is farther (0: no limit): how long,
    // in virtual time, work injected into the main lane may wait.
    Duration quantum{0};
    bool pin = false;  // WorkerPool::Options::pin
    // In a window, ask for each lane's state a few lanes ahead (VirtualTimeExecutor::prefetch):
    // worth it when the lanes' state no longer fits in the cache (a large swarm: at 10,000 robots
    // it took a sixth off the CPU time), a few instructions lost a lane when it does. No effect on
    // what runs.
    bool prefetch = false;
  };
  LockstepExecutor() : LockstepExecutor(Options{}) {}
  explicit LockstepExecutor(Options options);
  // Lanes go first (their activities are detached and released), then the main lane.
  ~LockstepExecutor() override;
  LockstepExecutor(const LockstepExecutor&) = delete;
  LockstepExecutor& operator=(const LockstepExecutor&) = delete;

  const Clock& clock() const override { return main_.clock(); }
  bool concurrent() const override { return false; }
  ActivitySlot& attach(Activity& activity, const ActivityOptions& options) override {
    return main_.attach(activity, options);
  }
  void inject(std::function<void()> fn) override { main_.inject(std::move(fn)); }
  bool on_own_context() const override { return main_.on_own_context(); }
  // Lane `index`, made on first use with its clock at now().
  Executor& lane(std::size_t index) override;
  ParallelFor* parallel() override { return &pool_; }
  // On the worker pool: each call's thread is lane i's guest (VirtualTimeExecutor::set_guest) for
  // the call. Calls for indices without a lane run after the others, on the calling thread.
  void for_each_lane(std::size_t n, const std::function<void(std::size_t)>& fn) override;
  // Runs `job` during the next window (B), beside the lanes, as one more item of the worker pool's
  // run; a run that stops before another window runs it before it returns.
  void run_alongside_lanes(std::function<void()> job) override;
  // Makes call i first in lane i's next window, on the worker that runs the lane (a lane's
  // readings then meet its handlers in that core's cache instead of being written by one pass
  // and read back by another); a run that stops before another window makes them before it
  // returns. Indices without a lane are called at once, on the calling thread. Within a window
  // the call is made as from a handler of the lane (VirtualTimeExecutor::call_as_handler), so a
  // task it notifies may take the notification at once, as in a single-lane run.
  void for_each_lane_before_its_window(std::size_t n, std::function<void(std::size_t)> fn) override;

  // Handles every event (main lane and lanes) up to and including `until`, then sets every clock
  // to `until`. Returns the number of events handled. stop() from a main-lane handler returns
  // early, at the sync instant where it was called.
  std::uint64_t run_until(Time until) { return run(until, false); }
  std::uint64_t run_for(Duration d) { return run_until(now() + d); }
  // Handles events until none is left (main lane and lanes) or `limit` is reached; the clocks
  // then stand at the latest event handled.
  std::uint64_t run_until_idle(Time limit = kTimeNever) { return run(limit, true); }
  // Makes the running run_*() return at the next sync instant (at once from a main-lane handler).
  void stop();
  // Runs the work injected into the main lane and the lanes now. Not during a run.
  std::size_t run_injected();
  // Waits up to `timeout` of real time for work injected into the main lane, then runs what was
  // injected anywhere (a lane's is not waited for: it runs at the latest in the next run).
  std::size_t wait_injected(std::chrono::nanoseconds timeout);

  Time now() const { return main_.now(); }
  unsigned threads() const { return pool_.threads(); }
  std::size_t lane_count() const { return lanes_.size(); }
  // Events queued on the main lane and every lane.
  std::size_t pending_events() const;

  // Where a run's wall-clock time went, for benchmarks: the share spent with the lanes running
  // (phase B) is what more threads can shorten; the rest (the world's step, the radio, the
  // observers) runs on one thread. Counted over every run_*() so far. The lanes' share is
  // estimated from a sample of the windows (the first kTimedWindows, then one in kTimedEvery): two
  // clock reads a window cost 60 ns, which for one robot was a twentieth of the framework's time a
  // step; a report of where the time went needs no more than this estimate.
  struct Stats {
    std::uint64_t windows = 0;  // phases (B) run
    // Wall clock inside phase (B), estimated; at most run_wall once a run has ended.
    std::chrono::nanoseconds lanes_wall{0};
    std::chrono::nanoseconds run_wall{0};  // wall clock inside run_*()
  };
  static constexpr std::uint64_t kTimedWindows = 64, kTimedEvery = 16;
  Stats stats() const;

 private:
  std::uint64_t run(Time limit, bool until_idle);
  // Phase (B) over every lane: events before `end` (or up to and including it when `inclusive`;
  // until idle when `idle`).
  std::uint64_t run_lanes(Time end, bool inclusive, bool idle);
  bool lanes_pending_by(Time t) const;
  // Makes the calls still waiting for a window (for_each_lane_before_its_window) now.
  void flush_before_window();

  const Options options_;
  WorkerPool pool_;
  VirtualTimeExecutor main_;
  std::vector<std::unique_ptr<VirtualTimeExecutor>> lanes_;
  std::vector<std::function<void()>> alongside_;  // run_alongside_lanes(), for the next window
  // for_each_lane_before_its_window(), for the next window: each with its count of lanes.
  std::vector<std::pair<std::size_t, std::function<void(std::size_t)>>> before_window_;
  // The window under way's share of the two above (run_lanes).
  std::vector<std::function<void()>> jobs_;
  std::vector<std::pair<std::size_t, std::function<void(std::size_t)>>> before_;
  std::atomic<bool> stop_requested_{false};
  bool running_ = false;
  Stats stats_;  // its lanes_wall is left at 0: stats() estimates it from the two below
  std::uint64_t timed_windows_ = 0;
  std::chrono::nanoseconds timed_lanes_wall_{0};  // over the timed windows
};

}  // namespace symb::kernel
