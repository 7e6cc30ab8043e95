#include "symb/kernel/bare_metal_executor.hpp"

namespace symb::kernel {

struct BareMetalExecutor::Slot final : ActivitySlot {
  BareMetalExecutor* exec = nullptr;
  Activity* activity = nullptr;  // null: free
  int priority = 0;
  Duration period{0};
  Time next_tick = kTimeNever;
  std::uint64_t order = 0;  // attach order: breaks priority ties
  bool started = false;
  bool suspended = false;
  bool input_pending = false;
  bool detaching = false;

  void wake() override {
    if (!detaching) input_pending = true;  // kept while suspended: handled after resume
  }
  void suspend() override {
    if (!detaching) suspended = true;
  }
  void resume() override {
    if (!suspended || detaching) return;
    suspended = false;
    if (started && period.count() > 0) next_tick = exec->clock_.now() + period;
  }
  void set_priority(int p) override { priority = p; }
  void set_period(Duration p) override {
    period = p;
    next_tick = started && p.count() > 0 ? exec->clock_.now() + p : kTimeNever;
  }
  void detach() override {
    if (detaching) return;
    detaching = true;
    exec->to_finalize_.push_back(this);
    if (!exec->running_) exec->finalize_pending();
  }
  // What this slot would do now, if anything: 1 start, 2 input, 3 tick, 0 nothing.
  int ready(Time now) const {
    if (activity == nullptr || detaching) return 0;
    if (!started) return 1;
    if (suspended) return 0;
    if (input_pending) return 2;
    if (period.count() > 0 && next_tick <= now) return 3;
    return 0;
  }
};

BareMetalExecutor::BareMetalExecutor(Duration tick, std::size_t capacity, std::function<void(const char*)> fail)
    : clock_(tick), fail_(std::move(fail)), slots_(new Slot[capacity]), capacity_(capacity) {
  for (std::size_t i = 0; i < capacity_; ++i) slots_[i].exec = this;
  inbox_.reserve(capacity_);
  to_finalize_.reserve(capacity_);
  stats_.capacity = capacity_;
}

BareMetalExecutor::~BareMetalExecutor() {
  for (std::size_t i = 0; i < used_; ++i)
    if (slots_[i].activity != nullptr && !slots_[i].detaching) slots_[i].detach();
  finalize_pending();
}

ActivitySlot& BareMetalExecutor::attach(Activity& activity, const ActivityOptions& options) {
  Slot* s = nullptr;
  for (std::size_t i = 0; i < used_ && s == nullptr; ++i)
    if (slots_[i].activity == nullptr) s = &slots_[i];
  if (s == nullptr) {
    if (used_ == capacity_) fail_("BareMetalExecutor: more activities than its capacity");
    s = &slots_[used_++];
  }
  s->activity = &activity;
  s->priority = options.priority;
  s->period = options.period;
  s->next_tick = kTimeNever;
  s->order = ++order_seq_;
  s->started = s->suspended = s->input_pending = s->detaching = false;
  ++stats_.activities;
  activity.on_activity_attached(*s);
  return *s;
}

void BareMetalExecutor::inject(std::function<void()> fn) {
  if (inbox_.size() == inbox_.capacity()) fail_("BareMetalExecutor: inject() past its capacity");
  inbox_.push_back(std::move(fn));
}

BareMetalExecutor::Slot* BareMetalExecutor::next_ready(Time now) {
  Slot* best = nullptr;
  for (std::size_t i = 0; i < used_; ++i) {
    Slot& s = slots_[i];
    if (s.ready(now) == 0) continue;
    if (best == nullptr || s.priority > best->priority || (s.priority == best->priority && s.order < best->order))
      best = &s;
  }
  return best;
}

bool BareMetalExecutor::run_one() {
  const bool was_running = running_;
  running_ = true;
  if (!inbox_.empty()) {
    // Work injected by work may be appended while this runs: index, not iterators.
    for (std::size_t i = 0; i < inbox_.size(); ++i) {
      std::function<void()> fn = std::move(inbox_[i]);
      fn();
      ++stats_.injected;
    }
    inbox_.clear();
  }
  const Time now = clock_.now();
  Slot* s = next_ready(now);
  if (s != nullptr) {
    switch (s->ready(now)) {
      case 1:
        s->started = true;
        if (s->period.count() > 0) s->next_tick = now + s->period;
        s->activity->on_activity_start();
        break;
      case 2:
        s->input_pending = false;
        s->activity->on_activity_input();
        break;
      default: {
        // From the due instant, not from now, so a period never drifts; a tick more than one
        // period late is not made up.
        Time next = s->next_tick + s->period;
        if (next <= now) {
          stats_.ticks_late += static_cast<std::uint64_t>((now - s->next_tick) / s->period);
          next = now + s->period;
        }
        s->next_tick = next;
        s->activity->on_activity_tick();
        break;
      }
    }
    ++stats_.handlers;
  }
  running_ = was_running;
  if (!running_) finalize_pending();
  return s != nullptr;
}

std::uint64_t BareMetalExecutor::run_ready() {
  stop_requested_ = false;
  std::uint64_t ran = 0;
  while (!stop_requested_ && run_one()) ++ran;
  return ran;
}

Time BareMetalExecutor::next_due() const {
  Time due = kTimeNever;
  for (std::size_t i = 0; i < used_; ++i) {
    const Slot& s = slots_[i];
    if (s.activity == nullptr || s.detaching) continue;
    if (!s.started || (!s.suspended && s.input_pending)) return clock_.now();
    if (!s.suspended && s.period.count() > 0 && s.next_tick < due) due = s.next_tick;
  }
  return due;
}

void BareMetalExecutor::finalize_pending() {
  // A stop handler may detach further activities; keep going until none is left.
  while (!to_finalize_.empty()) {
    Slot* s = to_finalize_.back();
    to_finalize_.pop_back();
    Activity* a = s->activity;
    if (s->started) {
      const bool was_running = running_;
      running_ = true;
      a->on_activity_stop();
      ++stats_.handlers;
      running_ = was_running;
    }
    s->activity = nullptr;
    --stats_.activities;
    a->on_activity_released();
  }
}

BareMetalStats BareMetalExecutor::stats() const { return stats_; }

}  // namespace symb::kernel
