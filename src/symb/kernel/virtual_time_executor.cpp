#include "symb/kernel/virtual_time_executor.hpp"

#include <cassert>

#include "symb/kernel/prefetch.hpp"

namespace symb::kernel {

struct VirtualTimeExecutor::Slot final : ActivitySlot {
  VirtualTimeExecutor* exec = nullptr;
  Activity* activity = nullptr;
  int priority = 0;
  // Bits of one byte, in the padding after the priority: with skip_before the slot would
  // otherwise take a heap block of 64 bytes rather than 56 (one a task: a swarm counts it).
  bool started : 1 = false;
  bool suspended : 1 = false;
  bool input_scheduled : 1 = false;
  bool input_while_suspended : 1 = false;
  bool detaching : 1 = false;
  Duration period{0};
  std::uint32_t generation = 0;
  // Bumped to cancel the tick chain in flight (suspend, new period).
  std::uint32_t tick_generation = 0;
  Time skip_before{0};  // skip_ticks_before(): no tick of the chain before this instant

  void wake() override {
    if (input_scheduled | detaching | suspended) [[unlikely]] {
      if (!detaching && suspended) input_while_suspended = true;
      return;
    }
    input_scheduled = true;
    exec->push_ready(
        Event{exec->clock_.now(), exec->seq_++, this, priority, generation, tick_generation, EventKind::kInput});
  }
  void suspend() override {
    if (suspended || detaching) return;
    suspended = true;
    ++tick_generation;
  }
  void resume() override {
    if (!suspended || detaching) return;
    suspended = false;
    ++tick_generation;
    skip_before = Time{0};
    if (started && period.count() > 0) exec->schedule(*this, EventKind::kTick, exec->clock_.now() + period);
    // An input event still queued will simply run now that the slot is awake again.
    if (input_while_suspended && !input_scheduled) {
      input_while_suspended = false;
      input_scheduled = true;
      exec->schedule(*this, EventKind::kInput, exec->clock_.now());
    }
  }
  bool can_run_inline() const override {
    // Outside a handler (injected work, a lockstep lane's idle phase) a detach would be carried
    // out at once, under the caller's feet: no. And only when the input event a wake would make
    // is the next one to be handled (nothing queued at this instant outranks it): then the run
    // differs from the woken one only in that the input comes before the rest of the handler
    // that made it, not after.
    if (!exec->running_ || (exec->current_ == nullptr && !exec->in_call_) || exec->current_ == this || !started ||
        suspended || detaching || input_scheduled)
      return false;
    if (!exec->ready_.empty() && exec->ready_.back().priority >= priority) return false;
    if (!exec->events_.empty() && exec->events_.front().time == exec->clock_.now() &&
        exec->events_.front().priority >= priority)
      return false;
    return exec->runner_.load(std::memory_order_relaxed) == std::this_thread::get_id();
  }
  void set_priority(int p) override { priority = p; }
  std::uint64_t skip_ticks_before(Time t) override {
    skip_before = t;
    return exec->skip_pending_tick(*this, t);
  }
  void set_period(Duration p) override {
    period = p;
    ++tick_generation;
    skip_before = Time{0};
    if (started && !suspended && !detaching && p.count() > 0)
      exec->schedule(*this, EventKind::kTick, exec->clock_.now() + p);
  }
  void detach() override {
    if (detaching) return;
    detaching = true;
    exec->to_finalize_.push_back(this);
    // Outside a run nobody else can be inside a handler: stop it now. Inside a run it stops as
    // soon as the handler that is running returns.
    if (!exec->running_) exec->finalize_pending();
  }
};

VirtualTimeExecutor::VirtualTimeExecutor() = default;

VirtualTimeExecutor::~VirtualTimeExecutor() {
  for (auto& s : slots_)
    if (s->activity != nullptr && !s->detaching) s->detach();
  finalize_pending();
}

ActivitySlot& VirtualTimeExecutor::attach(Activity& activity, const ActivityOptions& options) {
  Slot* s = nullptr;
  if (!free_slots_.empty()) {
    s = free_slots_.back();
    free_slots_.pop_back();
  } else {
    slots_.push_back(std::make_unique<Slot>());
    s = slots_.back().get();
    s->exec = this;
  }
  s->activity = &activity;
  s->priority = options.priority;
  s->period = options.period;
  s->started = s->suspended = s->input_scheduled = s->input_while_suspended = s->detaching = false;
  s->skip_before = Time{0};
  activity.on_activity_attached(*s);
  schedule(*s, EventKind::kStart, clock_.now());
  return *s;
}

void VirtualTimeExecutor::inject(std::function<void()> fn) {
  {
    std::lock_guard lock(inbox_mu_);
    inbox_.push_back(std::move(fn));
    inbox_pending_.store(true, std::memory_order_release);
  }
  inbox_cv_.notify_all();
}

std::size_t VirtualTimeExecutor::run_injected() {
  if (!inbox_pending_.load(std::memory_order_acquire)) return 0;
  std::vector<std::function<void()>> work;
  {
    std::lock_guard lock(inbox_mu_);
    work.swap(inbox_);
    inbox_pending_.store(false, std::memory_order_relaxed);
  }
  const bool was_running = running_;
  running_ = true;  // injected work may detach activities: defer that like a handler would
  for (auto& fn : work) fn();
  running_ = was_running;
  finalize_pending();
  return work.size();
}

void VirtualTimeExecutor::begin_call_as_handler() {
  assert(!running_ && "call_as_handler is not for inside a run");
  running_ = in_call_ = true;
  runner_.store(std::this_thread::get_id(), std::memory_order_relaxed);
}

void VirtualTimeExecutor::end_call_as_handler() {
  running_ = in_call_ = false;
  runner_.store(std::thread::id(), std::memory_order_relaxed);
  finalize_pending();
}

std::size_t VirtualTimeExecutor::wait_injected(std::chrono::nanoseconds timeout) {
  {
    std::unique_lock lock(inbox_mu_);
    inbox_cv_.wait_for(lock, timeout, [&] { return !inbox_.empty(); });
  }
  return run_injected();
}

[[gnu::always_inline]] void VirtualTimeExecutor::schedule(Slot& s, EventKind kind, Time t) {
  const Event e{t, seq_++, &s, s.priority, s.generation, s.tick_generation, kind};
  if (kind == EventKind::kInput && t == clock_.now())
    push_ready(e);
  else
    push_event(e);
}

[[gnu::always_inline]] void VirtualTimeExecutor::push_ready(const Event& e) {
  // Its sequence number is the newest, so it comes after every entry of its priority or higher:
  // those move up past it (the list holds zero to two entries in a step of a robot's chain).
  std::size_t i = ready_.size();
  ready_.push_back(e);
  while (i > 0 && ready_[i - 1].priority >= e.priority) {
    ready_[i] = ready_[i - 1];
    --i;
  }
  ready_[i] = e;
}

[[gnu::always_inline]] VirtualTimeExecutor::Event VirtualTimeExecutor::pop_next() {
  if (!ready_.empty()) {
    const Event& r = ready_.back();
    if (events_.empty() || events_.front().time != r.time || !first_at_instant(events_.front(), r)) {
      const Event e = r;
      ready_.pop_back();
      return e;
    }
  }
  return pop_event();
}

[[gnu::always_inline]] void VirtualTimeExecutor::push_event(const Event& e) {
  const Later later;
  std::size_t i = events_.size();
  events_.extend();
  while (i > 0) {
    const std::size_t parent = (i - 1) / 2;
    if (!later(events_[parent], e)) break;
    events_[i] = events_[parent];
    i = parent;
  }
  events_[i] = e;
}

[[gnu::always_inline]] VirtualTimeExecutor::Event VirtualTimeExecutor::pop_event() {
  const Later later;
  const Event top = events_.front();
  // The last event sifts down from the root, compared where it lies (a copy of it on the stack
  // was read back field by field: another forwarding stall).
  const std::size_t n = events_.size() - 1;
  if (n > 0) {
    const Event& last = events_[n];
    std::size_t i = 0;
    for (;;) {
      std::size_t child = 2 * i + 1;
      if (child >= n) break;
      if (child + 1 < n && later(events_[child], events_[child + 1])) ++child;
      if (!later(last, events_[child])) break;
      events_[i] = events_[child];
      i = child;
    }
    events_[i] = last;
  }
  events_.pop_back();
  return top;
}

std::uint64_t VirtualTimeExecutor::skip_pending_tick(Slot& s, Time t) {
  // A robot's lane holds a handful of events, so the tick is found by a look at each; in a large
  // heap the look is not worth it: the tick then runs when due and its handler finds nothing to
  // do, which is what leaving it out spares. During the slot's own tick none is pending (the
  // next is scheduled after it).
  constexpr std::size_t kLookLimit = 16;
  if (s.period.count() <= 0 || s.suspended || s.detaching || events_.size() > kLookLimit) return 0;
  for (std::size_t i = 0; i < events_.size(); ++i) {
    const Event& e = events_[i];
    if (e.slot != &s || e.kind != EventKind::kTick || e.generation != s.generation ||
        e.tick_generation != s.tick_generation)
      continue;
    if (e.time >= t) return 0;
    // Numbered now, as the tick that would have been scheduled when this one ran: at the instant
    // it moves to it comes after what was scheduled for that instant before, at its priority.
    Event moved = e;
    moved.time += s.period * ((t - e.time + s.period - Duration{1}) / s.period);
    moved.seq = seq_++;
    const Later later;
    for (;;) {  // later than it was: it can only sink
      std::size_t child = 2 * i + 1;
      if (child >= events_.size()) break;
      if (child + 1 < events_.size() && later(events_[child], events_[child + 1])) ++child;
      if (!later(moved, events_[child])) break;
      events_[i] = events_[child];
      i = child;
    }
    events_[i] = moved;
    return 1;
  }
  return 0;
}

void VirtualTimeExecutor::prefetch(int stage) const {
  switch (stage) {
    case 0: prefetch_bytes(this, sizeof(*this)); break;
    case 1:
      prefetch_bytes(events_.data(), events_.size() * sizeof(Event));
      prefetch_bytes(ready_.data(), ready_.size() * sizeof(Event));
      prefetch_bytes(slots_.data(), slots_.size() * sizeof(slots_[0]));
      break;
    case 2:
      for (const auto& s : slots_) prefetch_line(s.get());
      break;
    case 3:
      for (const auto& s : slots_)
        if (s->activity != nullptr) prefetch_line(s->activity);
      break;
    default:
      for (const auto& s : slots_)
        if (s->activity != nullptr) s->activity->prefetch(stage - 4);
      break;
  }
}

std::uint64_t VirtualTimeExecutor::run_until(Time until) {
  const std::uint64_t handled = run_until_idle(until);
  if (!stop_requested_ && until != kTimeNever) clock_.advance_to(until);
  return handled;
}

std::uint64_t VirtualTimeExecutor::run_before(Time until) {
  if (until <= clock_.now()) return run_until_idle(clock_.now() - Duration{1});  // only injected work
  const std::uint64_t handled = run_until_idle(until - Duration{1});             // integer nanoseconds: < until
  if (!stop_requested_ && until != kTimeNever) clock_.advance_to(until);
  return handled;
}

std::uint64_t VirtualTimeExecutor::run_until_idle(Time limit) {
  assert(!running_ && "run_until and run_until_idle are not reentrant");
  running_ = true;
  runner_.store(std::this_thread::get_id(), std::memory_order_relaxed);
  stop_requested_ = false;
  std::uint64_t handled = 0;
  for (;;) {
    if (inbox_pending_.load(std::memory_order_relaxed)) run_injected();
    if ((ready_.empty() && events_.empty()) || next_event_time() > limit || stop_requested_) break;
    const Event e = pop_next();
    clock_.advance_to(e.time);
    handle(e);
    ++handled;
    if (!to_finalize_.empty()) finalize_pending();
  }
  running_ = false;
  runner_.store(std::thread::id(), std::memory_order_relaxed);
  return handled;
}

[[gnu::always_inline]] void VirtualTimeExecutor::handle(const Event& e) {
  Slot& s = *e.slot;
  if (e.generation != s.generation || s.detaching) return;  // stale: the activity is gone
  current_ = &s;
  switch (e.kind) {
    case EventKind::kStart:
      s.started = true;
      s.activity->on_activity_start();
      if (s.period.count() > 0 && !s.suspended && !s.detaching) schedule(s, EventKind::kTick, e.time + s.period);
      break;
    case EventKind::kInput:
      if (s.suspended) {
        s.input_while_suspended = true;
        s.input_scheduled = false;
        break;
      }
      s.input_scheduled = false;
      s.activity->on_activity_input();
      break;
    case EventKind::kTick:
      if (e.tick_generation != s.tick_generation || s.suspended) break;
      s.activity->on_activity_tick();
      // Scheduled from the event time, not from now, so a period never drifts; ticks the handler
      // said it does not need are stepped over on the same grid.
      if (e.tick_generation == s.tick_generation && !s.suspended && !s.detaching && s.period.count() > 0) {
        Time next = e.time + s.period;
        if (s.skip_before > next) [[unlikely]]
          next += s.period * ((s.skip_before - next + s.period - Duration{1}) / s.period);
        schedule(s, EventKind::kTick, next);
      }
      break;
  }
  current_ = nullptr;
}

void VirtualTimeExecutor::finalize_pending() {
  // A stop handler may detach further activities; keep going until none is left.
  while (!to_finalize_.empty()) {
    Slot* s = to_finalize_.back();
    to_finalize_.pop_back();
    finalize(*s);
  }
}

void VirtualTimeExecutor::finalize(Slot& s) {
  Activity* a = s.activity;
  const bool started = s.started;
  ++s.generation;  // every event still queued for this slot is now stale
  if (started) {
    const bool was_running = running_;
    running_ = true;  // detaches from inside a stop handler are deferred like any other
    current_ = &s;
    a->on_activity_stop();
    current_ = nullptr;
    running_ = was_running;
  }
  s.activity = nullptr;
  free_slots_.push_back(&s);
  a->on_activity_released();
}

}  // namespace symb::kernel
