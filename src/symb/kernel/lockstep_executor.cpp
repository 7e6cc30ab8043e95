#include "symb/kernel/lockstep_executor.hpp"

#include <algorithm>
#include <cassert>
#include <thread>

namespace symb::kernel {

LockstepExecutor::LockstepExecutor(Options options)
    : options_(options), pool_(WorkerPool::Options{options.threads, options.pin}) {}

LockstepExecutor::~LockstepExecutor() { lanes_.clear(); }

Executor& LockstepExecutor::lane(std::size_t index) {
  assert(!running_ || main_.on_own_context());
  while (lanes_.size() <= index) {
    auto lane = std::make_unique<VirtualTimeExecutor>();
    lane->set_host(&main_);
    lane->run_until(main_.now());  // a lane made later starts at the common instant
    lanes_.push_back(std::move(lane));
  }
  return *lanes_[index];
}

void LockstepExecutor::for_each_lane(std::size_t n, const std::function<void(std::size_t)>& fn) {
  assert(main_.on_own_context() || !running_);
  const std::size_t with_lane = std::min(n, lanes_.size());
  pool_.run(with_lane, [&](std::size_t begin, std::size_t end) {
    const std::thread::id self = std::this_thread::get_id();
    for (std::size_t i = begin; i < end; ++i) {
      VirtualTimeExecutor& lane = *lanes_[i];
      lane.set_guest(self);
      struct Leave {
        VirtualTimeExecutor& lane;
        ~Leave() { lane.set_guest(std::thread::id{}); }
      } leave{lane};
      fn(i);
    }
  });
  for (std::size_t i = with_lane; i < n; ++i) fn(i);
}

void LockstepExecutor::stop() {
  stop_requested_.store(true, std::memory_order_relaxed);
  if (main_.on_own_context()) main_.stop();
}

std::size_t LockstepExecutor::run_injected() {
  std::size_t n = main_.run_injected();
  for (auto& lane : lanes_)
    if (lane->has_injected()) n += lane->run_injected();
  return n;
}

std::size_t LockstepExecutor::wait_injected(std::chrono::nanoseconds timeout) {
  return main_.wait_injected(timeout) + run_injected();
}

LockstepExecutor::Stats LockstepExecutor::stats() const {
  Stats s = stats_;
  if (timed_windows_ > 0) {
    const double per_window = static_cast<double>(timed_lanes_wall_.count()) / static_cast<double>(timed_windows_);
    const auto estimate =
        std::chrono::nanoseconds(static_cast<std::int64_t>(per_window * static_cast<double>(s.windows)));
    s.lanes_wall = s.run_wall.count() > 0 ? std::min(estimate, s.run_wall) : estimate;
  }
  return s;
}

std::size_t LockstepExecutor::pending_events() const {
  std::size_t n = main_.pending_events();
  for (const auto& lane : lanes_) n += lane->pending_events();
  return n;
}

namespace {

// An event queued at or before t, or injected work (kTimeNever also means "no event").
bool due_by(const VirtualTimeExecutor& e, Time t) {
  return (e.pending_events() > 0 && e.next_event_time() <= t) || e.has_injected();
}

}  // namespace

bool LockstepExecutor::lanes_pending_by(Time t) const {
  return std::any_of(lanes_.begin(), lanes_.end(), [t](const auto& lane) { return due_by(*lane, t); });
}

void LockstepExecutor::run_alongside_lanes(std::function<void()> job) {
  assert(main_.on_own_context() || !running_);
  alongside_.push_back(std::move(job));
}

void LockstepExecutor::for_each_lane_before_its_window(std::size_t n, std::function<void(std::size_t)> fn) {
  assert(main_.on_own_context() || !running_);
  for (std::size_t i = lanes_.size(); i < n; ++i) fn(i);
  if (!running_) {
    for_each_lane(std::min(n, lanes_.size()), fn);
    return;
  }
  before_window_.emplace_back(std::min(n, lanes_.size()), std::move(fn));
}

void LockstepExecutor::flush_before_window() {
  if (before_window_.empty()) return;
  std::vector<std::pair<std::size_t, std::function<void(std::size_t)>>> calls;
  calls.swap(before_window_);
  for (const auto& [n, fn] : calls) for_each_lane(n, fn);
}

std::uint64_t LockstepExecutor::run_lanes(Time end, bool inclusive, bool idle) {
  // This window's calls move to scratch vectors that keep their storage from window to window:
  // a swap with empty ones would make every window allocate them again.
  jobs_.swap(alongside_);
  before_.swap(before_window_);
  struct Clear {
    LockstepExecutor& ex;
    ~Clear() {
      ex.jobs_.clear();
      ex.before_.clear();
    }
  } clear{*this};
  if (lanes_.empty()) {
    for (auto& job : jobs_) job();
    return 0;
  }
  const bool timed = stats_.windows < kTimedWindows || stats_.windows % kTimedEvery == 0;
  const auto started = timed ? std::chrono::steady_clock::now() : std::chrono::steady_clock::time_point{};
  ++stats_.windows;
  struct Window {
    LockstepExecutor& ex;
    Time end;
    bool inclusive, idle;
    std::size_t first_lane;  // the jobs are the first items of the pool's run: the thread that
                             // takes them takes fewer lanes
    std::atomic<std::uint64_t> handled{0};
  } w{*this, end, inclusive, idle, jobs_.size()};
  // The pool's std::function holds one pointer, so it lives in the function object itself: a
  // closure capturing each variable would be allocated on the heap at every window.
  pool_.run(w.first_lane + lanes_.size(), [w = &w](std::size_t begin, std::size_t stop) {
    std::uint64_t n = 0;
    for (std::size_t i = begin; i < stop; ++i) {
      if (i < w->first_lane) {
        w->ex.jobs_[i]();
        continue;
      }
      // A lane's state is a chain of pointers (its executor, event heap, slots, activities, their
      // tasks and queues): in a large swarm each link comes from memory. Before lane i runs, lane
      // i + 2 kStages is asked for its first link, lane i + 2 (kStages - 1) for its second, lane
      // i + 2 for its last: by its turn a lane's loads have overlapped the runs of the lanes
      // before it. Two lanes a stage measured a few percent faster at 10,000 robots than one (a
      // link has two lanes' runs to arrive). Only within this call's range: the lanes past it may
      // be running on another thread.
      constexpr int kStages = VirtualTimeExecutor::kPrefetchStages;
      constexpr std::size_t kLanesAStage = 2;
      for (int stage = 0; w->ex.options_.prefetch && stage < kStages; ++stage) {
        const std::size_t ahead = i + kLanesAStage * static_cast<std::size_t>(kStages - stage);
        if (ahead >= w->first_lane && ahead < stop) w->ex.lanes_[ahead - w->first_lane]->prefetch(stage);
      }
      const std::size_t index = i - w->first_lane;
      VirtualTimeExecutor& lane = *w->ex.lanes_[index];
      if (!w->ex.before_.empty())
        lane.call_as_handler([w, index] {
          for (const auto& [count, fn] : w->ex.before_)
            if (index < count) fn(index);
        });
      if (w->idle)
        n += lane.run_until_idle(w->end);
      else if (w->inclusive)
        n += lane.run_until(w->end);
      else
        n += lane.run_before(w->end);
    }
    w->handled.fetch_add(n, std::memory_order_relaxed);
  });
  if (timed) {
    ++timed_windows_;
    timed_lanes_wall_ += std::chrono::steady_clock::now() - started;
  }
  return w.handled.load(std::memory_order_relaxed);
}

std::uint64_t LockstepExecutor::run(Time limit, bool until_idle) {
  assert(!running_ && "run_until and run_until_idle are not reentrant");
  running_ = true;
  // An exception from a handler (rethrown by the pool) leaves the executor usable for the caller
  // to tear down.
  struct NotRunning {
    bool& running;
    ~NotRunning() { running = false; }
  } not_running{running_};
  const auto started = std::chrono::steady_clock::now();
  stop_requested_.store(false, std::memory_order_relaxed);
  const auto stopped = [&] { return stop_requested_.load(std::memory_order_relaxed); };
  std::uint64_t handled = 0;
  for (;;) {
    // (A) The sync instant t: the main lane's events at t, the lanes idle.
    const Time t = main_.now();
    handled += main_.run_until_idle(t);
    if (stopped()) break;
    Time end = main_.next_event_time();
    if (options_.quantum.count() > 0 && t < kTimeNever - options_.quantum) end = std::min(end, t + options_.quantum);
    if (end <= limit && end != kTimeNever) {
      // (B) The window [t, end) on every lane; then the main lane's clock follows (work injected
      // into it from another thread meanwhile runs first, at t).
      handled += run_lanes(end, false, false);
      handled += main_.run_before(end);
      continue;
    }
    // The last window reaches `limit` itself, both ends included.
    if (until_idle) {
      handled += run_lanes(limit, true, true);
      Time latest = t;
      for (const auto& lane : lanes_) latest = std::max(latest, lane->now());
      for (auto& lane : lanes_) handled += lane->run_until(latest);  // no event of theirs is that early
      handled += main_.run_until(latest);
    } else {
      handled += run_lanes(limit, true, false);
      handled += main_.run_until(limit);
    }
    if (stopped()) break;
    // What the main lane did at the end (injected work) may have left work at or before it.
    if (due_by(main_, limit) || lanes_pending_by(until_idle ? main_.now() : limit)) continue;
    break;
  }
  // A run that stopped before another window still finishes what was to run beside it, on this
  // thread with no window open: as outside a run (a call made from these runs at once).
  running_ = false;
  flush_before_window();
  while (!alongside_.empty()) {
    std::vector<std::function<void()>> jobs;
    jobs.swap(alongside_);
    for (auto& job : jobs) job();
  }
  stats_.run_wall += std::chrono::steady_clock::now() - started;
  return handled;
}

}  // namespace symb::kernel
