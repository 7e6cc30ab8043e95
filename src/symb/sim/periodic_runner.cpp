#include "symb/sim/periodic_runner.hpp"

#include <stdexcept>

namespace symb::sim {

PeriodicRunner::PeriodicRunner(kernel::Executor& executor, Options options)
    : executor_(executor), options_(std::move(options)) {
  if (options_.period <= kernel::Duration::zero() || options_.period > std::chrono::seconds(1))
    throw std::invalid_argument("world runner '" + options_.name + "': the period must be in (0, 1 s]");
}

PeriodicRunner::~PeriodicRunner() { halt(); }

void PeriodicRunner::halt() {
  stop();
  // stop() waits under the thread executor; a virtual-time executor outside its run has released
  // us already. Anything else would be a runner destroyed from inside a handler.
  std::unique_lock lock(state_mu_);
  released_cv_.wait(lock, [&] { return !attached_; });
}

kernel::Status PeriodicRunner::start() {
  {
    std::lock_guard lock(state_mu_);
    if (attached_) return kernel::Error{"world runner '" + options_.name + "' is already running"};
    attached_ = true;
    error_.clear();
  }
  // Not under state_mu_: attach() calls on_activity_attached(), and a thread executor may already
  // run the first handler.
  executor_.attach(*this, kernel::ActivityOptions{options_.priority, options_.period, options_.name});
  return {};
}

void PeriodicRunner::stop() {
  kernel::ActivitySlot* slot = nullptr;
  {
    std::lock_guard lock(state_mu_);
    if (!attached_) return;
    slot = slot_;
    slot_ = nullptr;  // the slot is the executor's again once we are released
  }
  if (slot != nullptr) slot->detach();
  if (executor_.concurrent() && std::this_thread::get_id() != runner_thread_.load()) {
    std::unique_lock lock(state_mu_);
    released_cv_.wait(lock, [&] { return !attached_; });
  }
}

bool PeriodicRunner::running() const {
  std::lock_guard lock(state_mu_);
  return attached_ && slot_ != nullptr;
}

std::string PeriodicRunner::error() const {
  std::lock_guard lock(state_mu_);
  return error_;
}

void PeriodicRunner::on_activity_attached(kernel::ActivitySlot& slot) {
  std::lock_guard lock(state_mu_);
  slot_ = &slot;
}

void PeriodicRunner::on_activity_start() { runner_thread_.store(std::this_thread::get_id()); }

void PeriodicRunner::on_activity_released() {
  std::lock_guard lock(state_mu_);
  slot_ = nullptr;
  attached_ = false;
  runner_thread_.store(std::thread::id{});
  // Notified under the lock: a waiter may destroy the runner as soon as it gets the lock back.
  released_cv_.notify_all();
}

void PeriodicRunner::on_activity_tick() {
  // Made in place (a Status assigned after its construction moves a string every step).
  const kernel::Status st = [&]() -> kernel::Status {
    try {
      return step_once(executor_.clock().now());
    } catch (const std::exception& e) {
      return kernel::Error{e.what()};
    }
  }();
  if (!st) {
    fail(st.error());
    return;
  }
  // One writer (this handler): a plain store, not a locked read-modify-write per step.
  ticks_.store(ticks_.load(std::memory_order_relaxed) + 1, std::memory_order_release);
}

void PeriodicRunner::fail(const std::string& why) {
  kernel::ActivitySlot* slot = nullptr;
  std::string text = "world runner '" + options_.name + "' stopped: " + why;
  {
    std::lock_guard lock(state_mu_);
    error_ = text;
    slot = slot_;
    slot_ = nullptr;
  }
  if (slot != nullptr) slot->detach();
  on_failed(text);
}

}  // namespace symb::sim
