// RingBuffer: a fixed-capacity FIFO over storage allocated once at construction. It has no lock
// of its own: its owner decides whether one is needed (a virtual-time executor runs on one thread
// and needs none). When full, the owner chooses to refuse a new element or to overwrite the oldest.
#pragma once

#include <cassert>
#include <cstddef>
#include <utility>
#include <vector>

namespace symb::kernel {

template <class T>
class RingBuffer {
 public:
  explicit RingBuffer(std::size_t capacity) : slots_(capacity == 0 ? 1 : capacity) {}

  std::size_t capacity() const { return slots_.size(); }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  bool full() const { return size_ == slots_.size(); }

  // Appends; the caller has checked !full().
  void push(const T& v) {
    assert(!full());
    slots_[wrap(head_ + size_)] = v;
    ++size_;
  }
  // Appends, overwriting the oldest element when full. Returns true if one was overwritten.
  bool push_overwrite(const T& v) {
    if (!full()) {
      push(v);
      return false;
    }
    slots_[head_] = v;
    head_ = wrap(head_ + 1);
    return true;
  }
  // The i-th element from the oldest (i < size()).
  const T& at(std::size_t i) const { return slots_[wrap(head_ + i)]; }
  // The newest element (!empty()).
  T& back() { return slots_[wrap(head_ + size_ - 1)]; }
  T& front() { return slots_[head_]; }
  const T& front() const { return slots_[head_]; }
  void pop() {
    assert(!empty());
    head_ = wrap(head_ + 1);
    // An emptied buffer starts again at its first slot: a queue that holds one element at a time
    // (most task queues) then reuses one warm slot instead of walking its whole storage, a cache
    // miss per element once a swarm's queues no longer fit in the cache.
    if (--size_ == 0) head_ = 0;
  }
  // Moves the oldest element out.
  T take() {
    T v = std::move(slots_[head_]);
    pop();
    return v;
  }
  void clear() {
    while (!empty()) slots_[head_] = T{}, pop();
  }

 private:
  std::size_t wrap(std::size_t i) const { return i >= slots_.size() ? i - slots_.size() : i; }

  std::vector<T> slots_;
  std::size_t head_ = 0;
  std::size_t size_ = 0;
};

}  // namespace symb::kernel
