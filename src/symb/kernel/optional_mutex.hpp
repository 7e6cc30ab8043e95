// OptionalMutex: a mutex that can be switched off. Node data touched by several threads under the
// thread executor is touched by one thread only under the virtual-time executor; there the lock
// is skipped, which roughly halves the cost of a message delivery.
#pragma once

#include <mutex>

namespace symb::kernel {

class OptionalMutex {
 public:
  explicit OptionalMutex(bool enabled = true) : enabled_(enabled) {}
  void lock() {
    if (enabled_) mu_.lock();
  }
  void unlock() {
    if (enabled_) mu_.unlock();
  }
  bool enabled() const { return enabled_; }

 private:
  std::mutex mu_;
  bool enabled_;
};

}  // namespace symb::kernel
