// Executor: what runs activities (the os layer's tasks) and owns time. An activity is reactive:
// it is started, told when input is pending, ticked at its period, and stopped; it never blocks
// or sleeps. The same activity code runs unchanged under every executor:
//  - ThreadExecutor: one OS thread per activity, wall-clock time (the FreeRTOS model);
//  - VirtualTimeExecutor: discrete events on one thread, deterministic, faster than real time.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "symb/kernel/clock.hpp"
#include "symb/kernel/time.hpp"

namespace symb::kernel {

struct ActivityOptions {
  int priority = 0;    // higher runs first (virtual time) or is favoured by the OS (threads)
  Duration period{0};  // 0: never ticked
  std::string name;    // for thread names and diagnostics
};

// Implemented by whatever an executor runs. Every call for one activity happens on that
// activity's own execution context, one at a time, never two at once; the one exception is an
// input handler that the thread which woke the activity runs itself (RunWakesHere), still one
// handler at a time, with all the activity's earlier handlers' effects visible to it.
class ActivitySlot;
class ParallelFor;  // kernel/parallel_for.hpp

class Activity {
 public:
  virtual ~Activity() = default;
  // Called inside Executor::attach(), before any handler can run: the slot to signal from now on.
  virtual void on_activity_attached(ActivitySlot& slot) = 0;
  // First call, once, when the activity is attached.
  virtual void on_activity_start() = 0;
  // Input was signalled through the slot's wake(): handle what is pending.
  virtual void on_activity_input() = 0;
  // A period elapsed.
  virtual void on_activity_tick() = 0;
  // Last handler call, once, after detach (only if on_activity_start ran).
  virtual void on_activity_stop() = 0;
  // The executor will never touch this activity or its slot again; the owner may free it.
  virtual void on_activity_released() = 0;
  // A hint, with no effect on behaviour: the executor will soon run this activity's handlers, so
  // ask the memory system for what they read first (the lockstep executor's lanes, when a swarm's
  // state no longer fits in the cache). Called with levels 0 to kPrefetchLevels - 1, a while
  // apart: level 0 when only this object's first cache line was asked for, each next level for
  // what the blocks asked for at the previous one point to (reading a pointer from a block asked
  // for at the same level would wait for it). On the executor's thread, between the handlers.
  static constexpr int kPrefetchLevels = 4;
  virtual void prefetch(int /*level*/) const {}
};

// The executor's side of one attached activity. Owned by the executor and valid until the
// activity's on_activity_released(); every method may be called from any thread (and from inside
// any activity's handler), except under the single-threaded virtual-time executor where all
// calls come from its thread.
class RunWakesHere;

class ActivitySlot {
 public:
  virtual ~ActivitySlot() = default;
  // Input is pending: on_activity_input() will run soon (once for any number of wakes). Within a
  // RunWakesHere on the calling thread, an executor that can may run it on that thread instead.
  virtual void wake() = 0;
  // No handler runs while suspended; wakes are remembered; ticks resume one period after resume.
  virtual void suspend() = 0;
  virtual void resume() = 0;
  virtual void set_priority(int priority) = 0;
  virtual void set_period(Duration period) = 0;
  // A hint from the activity's own handler: its ticks before `t` would find nothing to do (a
  // watchdog whose deadline is still ahead; a controller that has just stepped at this instant on
  // new input, whose tick of the same instant would step no more). An executor may leave them
  // out; the chain keeps its phase, so the next tick is the first one of the period's grid at or
  // after `t`, the same instant it would have acted at anyway. Returns how many ticks that were
  // already due before `t` it left out now (a tick of this very instant not yet run, from a
  // message handler), so the activity can count them as the ticks would have; ticks left out
  // later, as the chain goes on, are not counted. Cleared by set_period() and resume(), which
  // start a chain afresh. Executors that tick in real time ignore it and return 0.
  virtual std::uint64_t skip_ticks_before(Time /*t*/) { return 0; }
  // Whether the caller may run this activity's input handling itself, right now, on the calling
  // thread, instead of waking it: true only for an executor that runs one handler at a time, when
  // the call comes from inside another activity's handler on its own context (so that a detach
  // the handling makes is deferred until that handler returns) and this activity is started,
  // awake, not detaching and has no input scheduled. Executors that cannot say so answer false.
  virtual bool can_run_inline() const { return false; }
  // Stops the activity: on_activity_stop() then on_activity_released(), after any handler that is
  // running returns. Safe to call from the activity's own handler.
  virtual void detach() = 0;

 protected:
  friend class RunWakesHere;
  // For a slot whose wake() claimed its activity for the thread's RunWakesHere (see there): runs
  // on_activity_input() on the calling thread, then gives the activity back to its executor.
  virtual void run_claimed_input() {}
};

// While alive on a thread that is outside every executor and has just made input pending (a
// network listener handing messages to tasks), lets the executors run the woken activities' input
// handlers on this thread when it ends, instead of waking their own: the hand-over of a wake
// costs a context switch on each side, and this thread has nothing else to do. An executor whose
// slots support it (the thread executor, not in realtime mode) claims an activity in wake() when
// the activity is idle: started, not suspended, not detached and running no handler on any
// thread; it then runs no handler of that activity (nor stops it) until the claimed run is done,
// so handlers still run one at a time, and input arriving meanwhile is its own thread's to
// handle. A busy activity, or one of any other executor, is woken as usual. Wakes made by the
// handlers it runs are plain wakes (they run on their own threads, as they would have). A scope
// may be opened inside a handler it runs (a listener called on that thread); it then handles its
// own wakes.
class RunWakesHere {
 public:
  RunWakesHere() : outer_(current_) { current_ = this; }
  ~RunWakesHere() {
    current_ = nullptr;
    for (std::size_t i = 0; i < count_; ++i) at(i)->run_claimed_input();
    current_ = outer_;
  }
  RunWakesHere(const RunWakesHere&) = delete;
  RunWakesHere& operator=(const RunWakesHere&) = delete;

  // For an executor's wake(): the scope open on this thread, or null.
  static RunWakesHere* current() { return current_; }
  // Whether `slot` is claimed here already (a second wake needs nothing: its run takes all input).
  bool holds(const ActivitySlot* slot) const {
    for (std::size_t i = 0; i < count_; ++i)
      if (at(i) == slot) return true;
    return false;
  }
  // For an executor's wake() that claimed `slot`'s activity: its input handler runs here.
  void add(ActivitySlot& slot) {
    if (count_ < kInline)
      inline_[count_] = &slot;
    else
      more_.push_back(&slot);
    ++count_;
  }

 private:
  static constexpr std::size_t kInline = 4;  // a listener wakes one receiver, seldom a few
  ActivitySlot* at(std::size_t i) const { return i < kInline ? inline_[i] : more_[i - kInline]; }

  static inline thread_local RunWakesHere* current_ = nullptr;
  RunWakesHere* outer_;
  ActivitySlot* inline_[kInline] = {};
  std::size_t count_ = 0;
  std::vector<ActivitySlot*> more_;
};

class Executor {
 public:
  virtual ~Executor() = default;
  virtual const Clock& clock() const = 0;
  // True when handlers of different activities may run at the same time, so shared state needs
  // locks; false for the single-threaded virtual-time executor.
  virtual bool concurrent() const = 0;
  // Starts running `activity`, which must outlive its on_activity_released().
  virtual ActivitySlot& attach(Activity& activity, const ActivityOptions& options) = 0;
  // Runs `fn` on the executor's own context as soon as it can: the way for a thread outside the
  // executor (a device reader, a socket) to hand work to nodes. The only executor call that may
  // come from any thread under every executor. The thread executor, whose node operations are
  // thread-safe anyway, runs `fn` at once on the calling thread; the virtual-time executor queues
  // it and runs it on its thread between events (and in run_*() calls with nothing else to do).
  virtual void inject(std::function<void()> fn) = 0;
  // True when the caller runs on the executor's own context, inside a run, where node calls
  // are as safe as in a handler: work that inject() would queue may then be done at once. Lets
  // a simulated device, published from a handler, skip the hand-over a foreign thread needs
  // (it costs a fifth of a message delivery). The thread executor's inject() is already direct.
  virtual bool on_own_context() const { return false; }
  // The executor for node number `index` of a group of nodes that meet one another only through
  // state stepped at fixed instants (a simulated world and its radio): an executor that runs such
  // nodes in parallel between those instants gives each its own lane; every other executor is
  // its own lane. Valid as long as the executor.
  virtual Executor& lane(std::size_t /*index*/) { return *this; }
  // Threads for a world's per-robot work between its steps, or null (do it serially).
  virtual ParallelFor* parallel() { return nullptr; }
  // Calls fn(i) for i in [0, n), each call free to act on lane(i)'s nodes as that lane's own
  // context would (a simulated device publishing to its robot). Only from this executor's own
  // context, while its lanes are idle, and fn(i) must touch no lane but lane(i): then an executor
  // whose lanes run on several threads may spread the calls over them, and what each lane sees
  // is the same as in order. Default: in order, on the calling thread.
  virtual void for_each_lane(std::size_t n, const std::function<void(std::size_t)>& fn) {
    for (std::size_t i = 0; i < n; ++i) fn(i);
  }
  // Work of this executor's own context that touches nothing a lane's nodes touch (a world's next
  // physics step, begun while the robots think: sim::World::begin_next_step). An executor whose
  // lanes run on several threads runs it during their next window, on one of its threads beside
  // them, and finishes it before the next instant at which its own context runs again, and before
  // run_*() returns; every other executor runs it at once. Only from this executor's own context.
  virtual void run_alongside_lanes(std::function<void()> job) { job(); }
  // As for_each_lane(), for calls whose effect only lane(i) itself reads (a device publishing its
  // readings to its robot): an executor whose lanes run in windows may make call i at the start
  // of lane i's next window, on that lane's thread, before any of its events, where what the call
  // touches is then in that thread's cache for the lane's own work. Every call is made before
  // lane i runs again, and before run_*() returns. `fn` must stay valid until then (it is kept).
  virtual void for_each_lane_before_its_window(std::size_t n, std::function<void(std::size_t)> fn) {
    for_each_lane(n, fn);
  }
};

}  // namespace symb::kernel
