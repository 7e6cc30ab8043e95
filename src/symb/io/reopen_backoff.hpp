// ReopenBackoff: when to try again to open a device that went away (a serial line whose USB
// adapter was pulled, a pseudo-terminal whose other end closed), and how long it was gone. A pure
// state machine over the caller's clock, shared by both ends of a hardware-in-the-loop link:
//
//   lost(t)       the device is found down at t (nothing happens when it is down already)
//   due(t)        an attempt may be made now: at once after the loss, then `first` after the
//                 first failed attempt, doubling after each one up to `most`
//   failed(t)     an attempt failed; returns the wait until the next one
//   reopened(t)   an attempt succeeded; returns how long this outage lasted
//
// Counters: losses == reopens + (down() ? 1 : 0); down_for(t) is the time down in all, the
// outage in progress included.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdint>

#include "symb/kernel/time.hpp"

namespace symb::io {

class ReopenBackoff {
 public:
  explicit ReopenBackoff(kernel::Duration first = std::chrono::milliseconds(100),
                         kernel::Duration most = std::chrono::seconds(2))
      : first_(first), most_(std::max(first, most)) {}

  void lost(kernel::Time t) {
    if (down_) return;
    down_ = true;
    since_ = t;
    next_ = t;
    wait_ = first_;
    attempts_ = 0;
    ++losses_;
  }
  bool down() const { return down_; }
  bool due(kernel::Time t) const { return down_ && t >= next_; }
  kernel::Duration failed(kernel::Time t) {
    ++attempts_;
    const kernel::Duration w = wait_;
    next_ = t + w;
    wait_ = std::min(most_, wait_ * 2);
    return w;
  }
  kernel::Duration reopened(kernel::Time t) {
    ++attempts_;
    const kernel::Duration outage = t - since_;
    total_ += outage;
    down_ = false;
    ++reopens_;
    return outage;
  }
  kernel::Duration down_for(kernel::Time t) const { return total_ + (down_ ? t - since_ : kernel::Duration{0}); }
  std::uint64_t losses() const { return losses_; }
  std::uint64_t reopens() const { return reopens_; }
  std::uint32_t attempts() const { return attempts_; }  // of the outage in progress (or the last)

 private:
  kernel::Duration first_;
  kernel::Duration most_;
  kernel::Duration wait_{0};
  kernel::Duration total_{0};
  kernel::Time since_{0};
  kernel::Time next_{0};
  std::uint64_t losses_ = 0;
  std::uint64_t reopens_ = 0;
  std::uint32_t attempts_ = 0;
  bool down_ = false;
};

}  // namespace symb::io
