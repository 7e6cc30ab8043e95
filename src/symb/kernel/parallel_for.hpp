// ParallelFor: runs n independent jobs, cut into contiguous ranges, on a fixed set of threads, and
// returns when every one is done. It is how a world computes per-robot work (IR sensing) on both
// cores between two physics steps. Jobs must not depend on which thread runs them or in which
// order: that is what keeps a run the same, bit for bit, whatever the number of threads.
#pragma once

#include <cstddef>
#include <functional>

namespace symb::kernel {

class ParallelFor {
 public:
  virtual ~ParallelFor() = default;
  // Threads that may run jobs at once (1: everything on the caller's thread).
  virtual unsigned threads() const = 0;
  // Calls fn(begin, end) over disjoint ranges that together cover [0, n), and returns when every
  // call has returned. When calls throw, the first exception is rethrown here after all calls
  // have finished. Not reentrant: fn must not call run() on the same object.
  virtual void run(std::size_t n, const std::function<void(std::size_t begin, std::size_t end)>& fn) = 0;
};

// Everything on the calling thread, in one range.
class SerialFor final : public ParallelFor {
 public:
  unsigned threads() const override { return 1; }
  void run(std::size_t n, const std::function<void(std::size_t, std::size_t)>& fn) override {
    if (n > 0) fn(0, n);
  }
};

}  // namespace symb::kernel
