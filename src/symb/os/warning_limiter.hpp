// WarningLimiter: a warning that is written at most once per interval, the one helper every task
// uses for it. Tasks meet the same
// bad input over and over (a sensor stuck out of range, a bus that keeps failing at 100 Hz); one
// log line per occurrence would flood the node's SysLog and push out everything else, while the
// exact numbers are kept in the tasks' counters anyway. The limiter lets the first occurrence
// through, then at most one per interval, each saying how many it stands for.
#pragma once

#include <cstdint>

#include "symb/kernel/time.hpp"

namespace symb::os {

class WarningLimiter {
 public:
  WarningLimiter() = default;
  explicit WarningLimiter(kernel::Duration interval) : interval_(interval) {}

  // Counts `n` occurrences at `now` (the task's node time). True when a warning should be
  // written now; it then stands for count() occurrences (these and the ones held back before).
  bool note(kernel::Time now, std::uint64_t n = 1) { return note(now, interval_, n); }
  // The same with the interval given here, for an owner whose interval is a live parameter.
  bool note(kernel::Time now, kernel::Duration interval, std::uint64_t n = 1) {
    held_ += n;
    if (written_ && now - last_ < interval) return false;
    written_ = true;
    last_ = now;
    count_ = held_;
    held_ = 0;
    return true;
  }
  std::uint64_t count() const { return count_; }
  void set_interval(kernel::Duration interval) { interval_ = interval; }

 private:
  kernel::Duration interval_ = std::chrono::seconds(1);
  kernel::Time last_{0};
  bool written_ = false;
  std::uint64_t held_ = 0;
  std::uint64_t count_ = 0;
};

}  // namespace symb::os
