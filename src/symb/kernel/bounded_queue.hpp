// BoundedQueue: a thread-safe FIFO of fixed capacity with blocking, timed operations, the
// kernel's counterpart of FreeRTOS xQueueSend/xQueueReceive. Used where a real thread must wait
// (device reader threads, the thread executor's plumbing); storage is allocated once.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <mutex>
#include <optional>

#include "symb/kernel/ring_buffer.hpp"

namespace symb::kernel {

// What a push into a full queue does.
enum class FullPolicy {
  kKeepNewest,  // overwrite the oldest element (sensor data: only the latest matters)
  kRefuse,      // refuse the new element; the caller counts it
};

enum class PushResult { kPushed, kOverwrote, kRefused };

template <class T>
class BoundedQueue {
 public:
  explicit BoundedQueue(std::size_t capacity) : ring_(capacity) {}

  std::size_t capacity() const { return ring_.capacity(); }
  std::size_t size() const {
    std::lock_guard lock(mu_);
    return ring_.size();
  }
  // Threads blocked in pop_for() or push_for() now: lets a test wait until a waiter really waits.
  std::size_t waiting() const {
    std::lock_guard lock(mu_);
    return waiting_;
  }

  // Never blocks: a full queue applies `policy`.
  PushResult push(const T& v, FullPolicy policy) {
    PushResult r = PushResult::kPushed;
    {
      std::lock_guard lock(mu_);
      if (ring_.full() && policy == FullPolicy::kRefuse) return PushResult::kRefused;
      if (ring_.push_overwrite(v)) r = PushResult::kOverwrote;
    }
    not_empty_.notify_one();
    return r;
  }

  // Waits up to `timeout` for room; false if the queue stayed full (or was closed).
  template <class Rep, class Period>
  bool push_for(const T& v, std::chrono::duration<Rep, Period> timeout) {
    {
      std::unique_lock lock(mu_);
      ++waiting_;
      const bool room = not_full_.wait_for(lock, timeout, [&] { return closed_ || !ring_.full(); });
      --waiting_;
      if (!room) return false;
      if (closed_) return false;
      ring_.push(v);
    }
    not_empty_.notify_one();
    return true;
  }

  std::optional<T> try_pop() {
    std::optional<T> v;
    {
      std::lock_guard lock(mu_);
      if (ring_.empty()) return v;
      v = ring_.take();
    }
    not_full_.notify_one();
    return v;
  }

  // Waits up to `timeout` for an element; nothing if none came (or the queue was closed and is
  // empty).
  template <class Rep, class Period>
  std::optional<T> pop_for(std::chrono::duration<Rep, Period> timeout) {
    std::optional<T> v;
    {
      std::unique_lock lock(mu_);
      ++waiting_;
      const bool any = not_empty_.wait_for(lock, timeout, [&] { return closed_ || !ring_.empty(); });
      --waiting_;
      if (!any) return v;
      if (ring_.empty()) return v;
      v = ring_.take();
    }
    not_full_.notify_one();
    return v;
  }

  // Wakes every waiter; pops still return what is queued, pushes that wait fail.
  void close() {
    {
      std::lock_guard lock(mu_);
      closed_ = true;
    }
    not_empty_.notify_all();
    not_full_.notify_all();
  }

 private:
  mutable std::mutex mu_;
  std::condition_variable not_empty_;
  std::condition_variable not_full_;
  RingBuffer<T> ring_;
  bool closed_ = false;
  std::size_t waiting_ = 0;
};

}  // namespace symb::kernel
