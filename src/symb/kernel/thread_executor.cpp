#include "symb/kernel/thread_executor.hpp"

#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <thread>

namespace symb::kernel {

class ThreadExecutor::Worker final : public ActivitySlot {
 public:
  Worker(ThreadExecutor& exec, Activity& activity, const ActivityOptions& o)
      : exec_(exec), activity_(activity), priority_(o.priority), period_(o.period), name_(o.name) {}

  void start() {
    thread_ = std::thread([this] { loop(); });
  }
  void join() {
    if (thread_.joinable()) thread_.join();
  }
  bool finished() const { return finished_.load(std::memory_order_acquire); }

  void wake() override {
    // Under SCHED_FIFO a handler must run at its own thread's priority: no guests then.
    RunWakesHere* here = exec_.options_.realtime ? nullptr : RunWakesHere::current();
    if (here != nullptr && here->holds(this)) return;
    bool notify = true;
    {
      std::lock_guard lock(mu_);
      // Not while this thread waits for a guest to finish: a stream of guests must not starve its
      // ticks (nor a wake already on its way to it).
      if (here != nullptr && started_ && !busy_ && !input_ && !worker_waits_ && !suspended_ && !detach_) {
        busy_ = guest_ = true;
        here->add(*this);
        return;
      }
      input_ = true;
      notify = !guest_;  // a guest's run ends by handing what came meanwhile to this thread
    }
    if (notify) cv_.notify_one();
  }
  void suspend() override {
    std::lock_guard lock(mu_);
    suspended_ = true;
  }
  void resume() override {
    {
      std::lock_guard lock(mu_);
      if (!suspended_) return;
      suspended_ = false;
      resumed_ = true;
    }
    cv_.notify_one();
  }
  void set_priority(int p) override {
    std::lock_guard lock(mu_);
    priority_ = p;
    priority_dirty_ = true;
  }
  void set_period(Duration p) override {
    {
      std::lock_guard lock(mu_);
      period_ = p;
      period_dirty_ = true;
    }
    cv_.notify_one();
  }
  void detach() override {
    {
      std::lock_guard lock(mu_);
      detach_ = true;
    }
    cv_.notify_one();
  }

 protected:
  void run_claimed_input() override {
    activity_.on_activity_input();
    std::lock_guard lock(mu_);
    busy_ = guest_ = false;
    // Notified under the lock: once this thread lets go, the worker may finish and be freed.
    if (worker_waits_ || input_) cv_.notify_one();
  }

 private:
  void apply_priority(int priority) {
    if (!exec_.options_.realtime || !exec_.realtime_ok_.load()) return;
    sched_param sp{};
    sp.sched_priority = ThreadExecutor::os_priority(priority);
    if (pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp) != 0) exec_.realtime_ok_.store(false);
  }

  void loop() {
    if (!name_.empty()) pthread_setname_np(pthread_self(), name_.substr(0, 15).c_str());
    const Clock& clock = exec_.clock_;
    std::unique_lock lock(mu_);
    const int first_priority = priority_;
    priority_dirty_ = false;
    Time next_tick = period_.count() > 0 ? clock.now() + period_ : kTimeNever;
    bool stop = detach_;
    lock.unlock();
    apply_priority(first_priority);
    if (!stop) activity_.on_activity_start();
    lock.lock();
    started_ = true;
    // Waits while a guest runs the input handler (RunWakesHere): handlers run one at a time.
    const auto wait_for_guest = [&] {
      worker_waits_ = true;
      cv_.wait(lock, [&] { return !busy_; });
      worker_waits_ = false;
    };
    while (!detach_) {
      const auto ready = [&] { return detach_ || resumed_ || period_dirty_ || (!suspended_ && input_); };
      if (suspended_ || next_tick == kTimeNever) {
        cv_.wait(lock, ready);
      } else {
        const auto deadline = exec_.clock_.epoch() + next_tick;
        cv_.wait_until(lock, deadline, ready);
      }
      if (busy_) wait_for_guest();
      if (detach_) break;
      if (priority_dirty_) {
        priority_dirty_ = false;
        apply_priority(priority_);  // only this thread may change its own scheduling
      }
      const Time now = clock.now();
      if (resumed_ || period_dirty_) {
        // Ticks restart one period after a resume or a new period.
        next_tick = period_.count() > 0 ? now + period_ : kTimeNever;
        resumed_ = period_dirty_ = false;
      }
      if (suspended_) continue;
      const bool input = input_;
      input_ = false;
      bool tick = false;
      if (next_tick != kTimeNever && now >= next_tick) {
        tick = true;
        next_tick += period_;
        if (next_tick <= now) next_tick = now + period_;  // overrun: skip missed ticks, keep going
      }
      if (!input && !tick) continue;
      busy_ = true;
      lock.unlock();
      if (input) activity_.on_activity_input();
      if (tick) activity_.on_activity_tick();
      lock.lock();
      busy_ = false;
    }
    if (busy_) wait_for_guest();  // stopped while a guest runs: it finishes first
    lock.unlock();
    if (!stop) activity_.on_activity_stop();
    activity_.on_activity_released();
    finished_.store(true, std::memory_order_release);
  }

  ThreadExecutor& exec_;
  Activity& activity_;
  std::mutex mu_;
  std::condition_variable cv_;
  int priority_;
  Duration period_;
  std::string name_;
  bool input_ = false;
  bool suspended_ = false;
  bool resumed_ = false;
  bool priority_dirty_ = false;
  bool period_dirty_ = false;
  bool detach_ = false;
  bool started_ = false;       // on_activity_start() returned: a guest may run input
  bool busy_ = false;          // a handler runs (this thread's, or a guest's claimed run)
  bool guest_ = false;         // busy_ with a guest's run
  bool worker_waits_ = false;  // this thread waits for the guest's run to end
  std::atomic<bool> finished_{false};
  std::thread thread_;
};

ThreadExecutor::ThreadExecutor(Options options) : options_(options), realtime_ok_(options.realtime) {}

ThreadExecutor::~ThreadExecutor() {
  std::list<std::unique_ptr<Worker>> workers;
  {
    std::lock_guard lock(mu_);
    workers.swap(workers_);
  }
  for (auto& w : workers) w->detach();
  for (auto& w : workers) w->join();
}

int ThreadExecutor::os_priority(int priority) {
  const int lo = sched_get_priority_min(SCHED_FIFO);
  const int hi = sched_get_priority_max(SCHED_FIFO);
  // Priority 0 sits in the middle of the range so both directions have room.
  return std::clamp((lo + hi) / 2 + priority, lo, hi);
}

ActivitySlot& ThreadExecutor::attach(Activity& activity, const ActivityOptions& options) {
  std::lock_guard lock(mu_);
  reap_finished_locked();
  workers_.push_back(std::make_unique<Worker>(*this, activity, options));
  Worker& w = *workers_.back();
  activity.on_activity_attached(w);
  w.start();
  return w;
}

std::size_t ThreadExecutor::thread_count() {
  std::lock_guard lock(mu_);
  reap_finished_locked();
  return workers_.size();
}

void ThreadExecutor::reap_finished_locked() {
  for (auto it = workers_.begin(); it != workers_.end();) {
    if ((*it)->finished()) {
      (*it)->join();
      it = workers_.erase(it);
    } else {
      ++it;
    }
  }
}

}  // namespace symb::kernel
