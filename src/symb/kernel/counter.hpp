// The stats pattern: single-writer counters.
//
// A task's counters are written by its own context only and read from any thread (the shell,
// symb run's summary, tests) while it runs. Each count is a Counter; a task keeps them together in
// a private struct whose snapshot() copies them into the plain stats struct its stats() getter
// returns (designated initialisers, so a counter out of the struct's order does not compile):
//
//   struct Counters {
//     kernel::Counter steps, ignored;
//     FooStats snapshot() const { return {.steps = steps.load(), .ignored = ignored.load()}; }
//   } counters_;
//   ...
//   counters_.steps.bump();                               // the task's context
//   FooStats Foo::stats() const { return counters_.snapshot(); }  // any thread
//
// No lock: bump() is a relaxed load and store instead of a locked read-modify-write (on a control
// step's path a dozen such counts cost as much as a message delivery), correct because there is one
// writer. A snapshot reads each count on its own, so two counts may be one step apart; a sum of
// counts (ignored = wrong_count + other) holds once the task is idle.
#pragma once

#include <atomic>
#include <cstdint>

namespace symb::kernel {

// Adds to an atomic that one thread writes and any thread may read.
inline void bump(std::atomic<std::uint64_t>& counter, std::uint64_t n = 1) {
  counter.store(counter.load(std::memory_order_relaxed) + n, std::memory_order_relaxed);
}

class Counter {
 public:
  // The writer's context only.
  void bump(std::uint64_t n = 1) { kernel::bump(value_, n); }
  void reset() { value_.store(0, std::memory_order_relaxed); }
  // Any thread.
  std::uint64_t load() const { return value_.load(std::memory_order_relaxed); }

 private:
  std::atomic<std::uint64_t> value_{0};
};

}  // namespace symb::kernel
