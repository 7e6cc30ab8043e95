// BareMetalExecutor: the executor of a microcontroller without an RTOS (the board image,
// docs/board.md), in the way FreeRTOS schedules tasks on one core: run-to-completion handlers,
// the highest priority ready activity first, periodic activities released by a tick interrupt
// (SysTick). It makes no OS calls and takes no lock, so it is the same file on the host, where
// its ordering is unit-tested, and on the board.
//
// Time is the tick count: the tick interrupt calls on_tick_interrupt(), the only call allowed from
// an interrupt, and now() is ticks x tick period. Everything else runs on the one context that
// calls run_ready(): the board's main loop, which sleeps (WFI) whenever run_ready() returns with
// nothing ready.
//
// Which handler runs next: among activities with something to do (a start, pending input, a tick
// that is due), the highest priority; among equals, the one attached first. For one activity its
// start comes first, then its input, then its tick. A tick due more than one period late is not
// made up: the next one is set one period after now and the skipped ones are counted (ticks_late),
// as an overrun of a FreeRTOS vTaskDelayUntil task would be.
//
// No heap after start-up: slots come from a fixed array reserved at construction (capacity);
// inject() work waits in a vector reserved at construction too. Attaching past the capacity, or
// injecting past it, is refused by stopping in fail() with the reason (a board cannot grow).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "symb/kernel/executor.hpp"

namespace symb::kernel {

// Time counted in ticks of a fixed period; only the tick interrupt moves it.
class TickClock final : public Clock {
 public:
  explicit TickClock(Duration tick) : tick_(tick) {}
  Time now() const override { return tick_ * ticks_.load(std::memory_order_relaxed); }
  std::uint32_t ticks() const { return ticks_.load(std::memory_order_relaxed); }
  Duration tick() const { return tick_; }
  // The tick interrupt: one tick more. A 32-bit count is one store on a Cortex-M3 (no lock); at
  // 1 ms it lasts 49 days.
  void advance() { ticks_.store(ticks_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed); }

 private:
  Duration tick_;
  std::atomic<std::uint32_t> ticks_{0};
};

struct BareMetalStats {
  std::uint64_t handlers = 0;    // handler calls (start, input, tick, stop)
  std::uint64_t ticks_late = 0;  // periods skipped because a tick was handled more than one late
  std::uint64_t injected = 0;    // inject() calls run
  std::size_t activities = 0;    // attached now
  std::size_t capacity = 0;
};

class BareMetalExecutor final : public Executor {
 public:
  // `fail` is called (and must not return) when a fixed capacity is exceeded.
  BareMetalExecutor(Duration tick, std::size_t capacity, std::function<void(const char*)> fail);
  ~BareMetalExecutor() override;
  BareMetalExecutor(const BareMetalExecutor&) = delete;
  BareMetalExecutor& operator=(const BareMetalExecutor&) = delete;

  const Clock& clock() const override { return clock_; }
  bool concurrent() const override { return false; }
  ActivitySlot& attach(Activity& activity, const ActivityOptions& options) override;
  // Only from the executor's own context (never from an interrupt): runs `fn` before the next
  // handler.
  void inject(std::function<void()> fn) override;
  bool on_own_context() const override { return running_; }

  // The tick interrupt (SysTick); the only call allowed from an interrupt.
  void on_tick_interrupt() { clock_.advance(); }
  // Runs handlers while any activity is ready; returns how many ran. A handler may call stop().
  std::uint64_t run_ready();
  // Runs at most one handler (the next one by the rules above); false when none was ready.
  bool run_one();
  // The earliest instant at which a tick is due, or kTimeNever: the main loop may sleep until
  // then (or until an interrupt brings input).
  Time next_due() const;
  void stop() { stop_requested_ = true; }
  Time now() const { return clock_.now(); }
  BareMetalStats stats() const;

 private:
  struct Slot;
  Slot* next_ready(Time now);
  void finalize_pending();

  TickClock clock_;
  std::function<void(const char*)> fail_;
  std::unique_ptr<Slot[]> slots_;
  std::size_t capacity_;
  std::size_t used_ = 0;  // slots [0, used_) were handed out at least once
  std::uint64_t order_seq_ = 0;
  std::vector<std::function<void()>> inbox_;
  std::vector<Slot*> to_finalize_;
  bool running_ = false;
  bool stop_requested_ = false;
  BareMetalStats stats_;
};

}  // namespace symb::kernel
