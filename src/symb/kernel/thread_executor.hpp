// ThreadExecutor: one OS thread per activity, in real (wall-clock) time, as FreeRTOS runs one
// task per thread of control. Each thread waits, with a timeout up to its next tick, for a wake;
// then handles pending input and due ticks. With Options::realtime the threads run under
// SCHED_FIFO at priorities mapped from the activities' priorities where the process is allowed
// to; otherwise (the default, and the fallback when refused) all threads share SCHED_OTHER and
// priority only orders events under the virtual-time executor: a documented best effort. Outside
// realtime mode, a thread that wakes an idle activity within a RunWakesHere (executor.hpp) runs
// its input handler itself, still one handler at a time: no context switch to hand it over.
#pragma once

#include <atomic>
#include <condition_variable>
#include <list>
#include <memory>
#include <mutex>

#include "symb/kernel/executor.hpp"

namespace symb::kernel {

class ThreadExecutor final : public Executor {
 public:
  struct Options {
    bool realtime = false;  // try SCHED_FIFO; busy tasks at real-time priority can starve a machine
  };
  ThreadExecutor() : ThreadExecutor(Options{}) {}
  explicit ThreadExecutor(Options options);
  // Detaches whatever is still attached and joins every thread.
  ~ThreadExecutor() override;
  ThreadExecutor(const ThreadExecutor&) = delete;
  ThreadExecutor& operator=(const ThreadExecutor&) = delete;

  const Clock& clock() const override { return clock_; }
  bool concurrent() const override { return true; }
  ActivitySlot& attach(Activity& activity, const ActivityOptions& options) override;
  void inject(std::function<void()> fn) override { fn(); }

  // Whether SCHED_FIFO was asked for and granted (false once any thread was refused).
  bool realtime_active() const { return realtime_ok_.load(); }
  // Threads attached and not yet joined (for tests and diagnostics).
  std::size_t thread_count();
  // Maps an activity priority (any int) onto SCHED_FIFO's 1..99.
  static int os_priority(int priority);

 private:
  class Worker;
  void reap_finished_locked();

  WallClock clock_;
  Options options_;
  std::atomic<bool> realtime_ok_;
  std::mutex mu_;
  std::list<std::unique_ptr<Worker>> workers_;
};

}  // namespace symb::kernel
