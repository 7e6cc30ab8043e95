// OptionalMutex: a mutex that can be switched off. Node data touched by several threads under the
// thread executor is touched by one thread only under the virtual-time executor; there the lock
// is skipped, which roughly halves the cost of a message delivery, and not even allocated, which
// keeps a task's bookkeeping small for swarms of thousands of tasks.
#pragma once

#include <memory>
#include <mutex>

namespace symb::kernel {

class OptionalMutex {
 public:
  explicit OptionalMutex(bool enabled = true) : mu_(enabled ? std::make_unique<std::mutex>() : nullptr) {}
  void lock() {
    if (mu_) mu_->lock();
  }
  void unlock() {
    if (mu_) mu_->unlock();
  }
  bool enabled() const { return mu_ != nullptr; }

 private:
  std::unique_ptr<std::mutex> mu_;
};

}  // namespace symb::kernel
