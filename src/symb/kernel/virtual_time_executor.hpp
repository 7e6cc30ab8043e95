// VirtualTimeExecutor: a discrete-event executor on one thread. Events (start, pending input,
// tick, stop) are ordered by virtual time, then by activity priority (higher first), then by the
// order they were scheduled, so the same inputs always give the same run, bit for bit. Handlers
// take no virtual time; a message sent at t is handled at t. Many nodes (a swarm) share one
// executor and so one timeline.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "symb/kernel/executor.hpp"

namespace symb::kernel {

class VirtualTimeExecutor final : public Executor {
 public:
  VirtualTimeExecutor();
  ~VirtualTimeExecutor() override;
  VirtualTimeExecutor(const VirtualTimeExecutor&) = delete;
  VirtualTimeExecutor& operator=(const VirtualTimeExecutor&) = delete;

  const Clock& clock() const override { return clock_; }
  bool concurrent() const override { return false; }
  ActivitySlot& attach(Activity& activity, const ActivityOptions& options) override;
  void inject(std::function<void()> fn) override;
  // Also true on the thread of a host executor's run (set_host): see there.
  bool on_own_context() const override {
    const std::thread::id self = std::this_thread::get_id();
    return runner_.load(std::memory_order_relaxed) == self ||
           (host_ != nullptr && host_->runner_.load(std::memory_order_relaxed) == self) ||
           guest_.load(std::memory_order_relaxed) == self;
  }
  // Lets the thread inside `host`'s run_*() act as this executor's own context. For an executor
  // that runs this one only at moments when `host` is not running (a lane of a lockstep executor,
  // whose main lane is the host): then the host's handlers may make this executor's nodes' calls
  // directly, as their own handlers would, instead of injecting them. Null: no host.
  void set_host(const VirtualTimeExecutor* host) { host_ = host; }
  // Lets `guest` act as this executor's own context until it is reset (an empty id): for a
  // worker of a lockstep executor's for_each_lane(), which calls into this lane alone while every
  // lane is idle.
  void set_guest(std::thread::id guest) { guest_.store(guest, std::memory_order_relaxed); }
  // Calls fn() on the calling thread at now() as if a handler of this executor made the call: for
  // what a lockstep executor calls into a lane just before the lane's window (a device publishing
  // its robot's readings), while the lane is idle. A detach fn asks for waits for fn's end, and
  // an activity fn wakes may take its input at once, on the terms it would inside a handler
  // (ActivitySlot::can_run_inline): the run is the one a wake would give, but for that input
  // coming before the rest of fn. Not from inside a run of this executor.
  template <class F>
  void call_as_handler(F&& fn) {
    struct Leave {
      VirtualTimeExecutor& e;
      ~Leave() { e.end_call_as_handler(); }
    };
    begin_call_as_handler();
    Leave leave{*this};
    fn();
  }
  // Runs the injected work now (run_*() also does, between events). Returns how much ran.
  std::size_t run_injected();
  // Waits up to `timeout` of real time for injected work, then runs it: lets a caller pace a
  // virtual-time run against the outside world (a shell, a serial line) without spinning.
  std::size_t wait_injected(std::chrono::nanoseconds timeout);

  // Handles every event up to and including `until`, then sets the clock to `until`. Returns the
  // number of events handled. A handler may call stop() to return early.
  std::uint64_t run_until(Time until);
  std::uint64_t run_for(Duration d) { return run_until(clock_.now() + d); }
  // Handles events until none is left or `limit` is reached.
  std::uint64_t run_until_idle(Time limit = kTimeNever);
  // Handles every event strictly earlier than `until`, then sets the clock to `until`: one window
  // [now, until) of a lockstep run, whose instant `until` belongs to the next window.
  std::uint64_t run_before(Time until);
  // The time of the next queued event (possibly one that will turn out stale), or kTimeNever.
  Time next_event_time() const {
    if (!ready_.empty()) return ready_.back().time;
    return events_.empty() ? kTimeNever : events_.front().time;
  }
  // True when injected work waits (cheap: one atomic load).
  bool has_injected() const { return inbox_pending_.load(std::memory_order_acquire); }
  // Makes the running run_*() return after the current handler.
  void stop() { stop_requested_ = true; }
  Time now() const { return clock_.now(); }
  std::size_t pending_events() const { return events_.size() + ready_.size(); }
  // For a caller that runs many executors one after another (the lockstep executor's lanes): asks
  // the memory system for what the next run will read, one level of pointers a call, so that
  // calls a few executors ahead overlap their loads with the runs in between. Stage 0: the object
  // itself; 1: the event heap and the slot table; 2: the slots; 3: their activities' first line;
  // then Activity::prefetch's levels. A stage expects the earlier ones to have been asked for a
  // while ago; only a hint, with no effect on behaviour.
  static constexpr int kPrefetchStages = 4 + Activity::kPrefetchLevels;
  void prefetch(int stage) const;

 private:
  struct Slot;
  enum class EventKind : std::uint8_t { kStart, kInput, kTick };
  struct Event {  // 40 bytes: the fields are ordered to leave no padding
    Time time;
    std::uint64_t seq;
    Slot* slot;
    int priority;
    std::uint32_t generation;
    std::uint32_t tick_generation;
    EventKind kind;
  };
  // The events of the heap or of the ready list: a vector that grows and never shrinks (a run's
  // queue keeps about one size), its append in line. std::vector's was a call at every scheduled
  // event, and one step of a robot schedules three to five.
  class EventList {
   public:
    std::size_t size() const { return size_; }
    bool empty() const { return size_ == 0; }
    Event& operator[](std::size_t i) { return slots_[i]; }
    const Event& operator[](std::size_t i) const { return slots_[i]; }
    const Event& front() const { return slots_[0]; }
    const Event& back() const { return slots_[size_ - 1]; }
    const Event* data() const { return slots_.data(); }
    // One more event at the end, its value unset.
    void extend() {
      if (size_ == slots_.size()) [[unlikely]]
        grow();
      ++size_;
    }
    void push_back(const Event& e) {
      extend();
      slots_[size_ - 1] = e;
    }
    void pop_back() { --size_; }

   private:
    [[gnu::noinline]] void grow() { slots_.resize(slots_.empty() ? 16 : 2 * slots_.size()); }
    std::vector<Event> slots_;
    std::size_t size_ = 0;
  };
  struct Later {
    bool operator()(const Event& a, const Event& b) const {
      if (a.time != b.time) return a.time > b.time;
      if (a.priority != b.priority) return a.priority < b.priority;
      return a.seq > b.seq;
    }
  };
  // Of two events at one instant, whether `a` comes before `b`.
  static bool first_at_instant(const Event& a, const Event& b) {
    return a.priority != b.priority ? a.priority > b.priority : a.seq < b.seq;
  }

  // The event path below is declared inline and defined [[gnu::always_inline]] in the .cpp, its
  // only user: as calls, these small functions cost a robot's step a sixth more in the executor
  // (callgrind, the 1-robot maze: 179 instructions a step).
  inline void schedule(Slot& s, EventKind kind, Time t);
  // A binary heap by hand rather than std::priority_queue: std::push_heap writes the new event
  // into the vector and reads it straight back, a store-forwarding stall that made scheduling a
  // tenth of a message delivery. Here the event stays in registers until its place is found.
  inline void push_event(const Event& e);
  inline Event pop_event();
  // Slot::skip_ticks_before's work: the slot's tick of its current chain that is due before `t`
  // moves to the first instant of its grid at or after `t`. Returns 1 if it did, else 0.
  std::uint64_t skip_pending_tick(Slot& s, Time t);
  // Input scheduled at the current instant (a wake: most events of a step) skips the heap: it
  // joins `ready_`, a short list in handling order, and the next event is the better of its last
  // entry and the heap's top. The order is the heap's own (time, priority, schedule order).
  inline void push_ready(const Event& e);
  inline Event pop_next();
  inline void handle(const Event& e);
  void finalize(Slot& s);
  void finalize_pending();
  void begin_call_as_handler();
  void end_call_as_handler();

  std::mutex inbox_mu_;
  std::condition_variable inbox_cv_;
  std::vector<std::function<void()>> inbox_;
  std::atomic<bool> inbox_pending_{false};

  VirtualClock clock_;
  EventList events_;  // a heap: events_[0] is the next to handle (see Later)
  // Events at now() (push_ready): the last one is handled first. Never older than now(): the
  // clock moves on only once they are all handled.
  EventList ready_;
  std::vector<std::unique_ptr<Slot>> slots_;
  std::vector<Slot*> free_slots_;
  std::vector<Slot*> to_finalize_;
  Slot* current_ = nullptr;
  bool in_call_ = false;  // inside call_as_handler(): a handler, though no slot's
  std::uint64_t seq_ = 0;
  bool running_ = false;
  // The thread inside run_*(), read by on_own_context() from any thread; empty outside a run.
  std::atomic<std::thread::id> runner_{};
  bool stop_requested_ = false;
  const VirtualTimeExecutor* host_ = nullptr;
  std::atomic<std::thread::id> guest_{};
};

}  // namespace symb::kernel
