// Clock: where a node reads the time. Task code never reads the wall clock itself; it asks its
// node, which asks the clock its executor provides. A WallClock follows std::steady_clock; a
// VirtualClock only moves when the virtual-time executor advances it, which is what makes
// simulated runs repeatable and faster than real time.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>

#include "symb/kernel/time.hpp"

namespace symb::kernel {

class Clock {
 public:
  virtual ~Clock() = default;
  // The current instant, counted from this clock's epoch.
  virtual Time now() const = 0;
  // now(), read straight from memory when the clock is a counter there (a virtual clock): a node
  // asks for the time at every send and at most handlers, and a virtual call each time was a
  // tenth of a robot step's framework cost outside the handlers' own work.
  Time read() const { return counter_ != nullptr ? Time{counter_->load(std::memory_order_relaxed)} : now(); }

 protected:
  // The nanoseconds this clock's now() returns, for a clock that keeps them in one atomic.
  const std::atomic<std::int64_t>* counter_ = nullptr;
};

// Monotonic real time, counted from construction.
class WallClock final : public Clock {
 public:
  WallClock() : epoch_(std::chrono::steady_clock::now()) {}
  Time now() const override { return std::chrono::duration_cast<Time>(std::chrono::steady_clock::now() - epoch_); }
  // The steady_clock instant this clock counts from, for timed waits on real primitives.
  std::chrono::steady_clock::time_point epoch() const { return epoch_; }

 private:
  std::chrono::steady_clock::time_point epoch_;
};

// Time that moves only when told to. Reads are atomic so that a thread outside the executor (a
// shell, a monitor) may read it without a data race; only the executor writes it.
class VirtualClock final : public Clock {
 public:
  VirtualClock() { counter_ = &now_; }
  VirtualClock(const VirtualClock&) = delete;
  VirtualClock& operator=(const VirtualClock&) = delete;
  Time now() const override { return Time{now_.load(std::memory_order_relaxed)}; }
  // Moves the clock; instants never go backwards, so an earlier value is ignored.
  void advance_to(Time t) {
    if (t.count() > now_.load(std::memory_order_relaxed)) now_.store(t.count(), std::memory_order_relaxed);
  }

 private:
  std::atomic<std::int64_t> now_{0};
};

}  // namespace symb::kernel
