// The board's port of the standard library's thread primitives. Debian's arm-none-eabi libstdc++
// is built for a single-threaded target (no gthreads), so <mutex> and <condition_variable> declare
// no std::mutex and no std::condition_variable. The kernel, os, io, robot and control layers lock
// them because on Linux their tasks may run on several threads; on the board every task handler
// runs to completion on one context (BareMetalExecutor) and interrupt handlers touch only the
// UART's own ring buffers, never a node, so a lock that does nothing is a correct lock here.
// Force-included into every board translation unit (-include), so no shared source file changes.
// A wait that would block cannot be satisfied by anyone on one context: it stops the board
// (symb_board_fatal), which the image reports; the board's code paths never wait.
#pragma once

#include <chrono>

#include <bits/std_mutex.h>

[[noreturn]] void symb_board_fatal(const char* why);

namespace std {

#ifndef _GLIBCXX_HAS_GTHREADS
class mutex {
 public:
  constexpr mutex() noexcept = default;
  mutex(const mutex&) = delete;
  mutex& operator=(const mutex&) = delete;
  void lock() {}
  bool try_lock() { return true; }
  void unlock() {}
};

class recursive_mutex : public mutex {};

enum class cv_status { no_timeout, timeout };

class condition_variable {
 public:
  condition_variable() noexcept = default;
  condition_variable(const condition_variable&) = delete;
  condition_variable& operator=(const condition_variable&) = delete;
  void notify_one() noexcept {}
  void notify_all() noexcept {}
  template <class Lock>
  void wait(Lock&) {
    symb_board_fatal("condition_variable::wait on a single-context board");
  }
  template <class Lock, class Pred>
  void wait(Lock&, Pred pred) {
    if (!pred()) symb_board_fatal("condition_variable::wait on a single-context board");
  }
  template <class Lock, class Rep, class Period>
  cv_status wait_for(Lock&, const chrono::duration<Rep, Period>&) {
    return cv_status::timeout;
  }
  template <class Lock, class Rep, class Period, class Pred>
  bool wait_for(Lock&, const chrono::duration<Rep, Period>&, Pred pred) {
    return pred();
  }
  template <class Lock, class Clock, class Duration>
  cv_status wait_until(Lock&, const chrono::time_point<Clock, Duration>&) {
    return cv_status::timeout;
  }
  template <class Lock, class Clock, class Duration, class Pred>
  bool wait_until(Lock&, const chrono::time_point<Clock, Duration>&, Pred pred) {
    return pred();
  }
};
#endif

}  // namespace std
