// eventually: waits for a condition that another thread or process makes true (a worker that
// ticked, a peer that answered, a reader that blocked), polling it until it holds or a deadline
// passes, so a test never sleeps a fixed time and never hangs. The deadline is generous because a
// passing test returns as soon as the condition holds: only a failing one waits it out, and a
// sanitizer build runs ten times slower than a release one.
#pragma once

#include <chrono>
#include <functional>
#include <thread>

namespace symb::testing {

inline constexpr std::chrono::seconds kEventuallyLimit{20};

// Polls `cond` every millisecond (the other side gets the CPU in between) until it holds or
// `limit` passes; returns whether it held. `cond` is asked once more after the deadline, so a
// condition that became true while the poller slept is not reported as a timeout.
inline bool eventually(const std::function<bool()>& cond, std::chrono::nanoseconds limit = kEventuallyLimit) {
  const auto end = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < end) {
    if (cond()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return cond();
}

}  // namespace symb::testing
