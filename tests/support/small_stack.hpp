// Runs a function on a thread with a small native stack, so a test shows that a parser's
// recursion bound leaves ample headroom: the thread executor's threads and the main thread have
// the default 8 MiB (RLIMIT_STACK); a parser that fits in a small fraction of that also fits
// under ASan, whose frames are several times larger.
#pragma once

#include <pthread.h>

#include <cstddef>
#include <functional>

namespace symb::test_support {

// 256 KiB: 1/32 of the threads' default stack.
inline constexpr std::size_t kSmallStackBytes = 256 * 1024;

// Calls `fn` on a new thread with `stack_bytes` of stack and waits for it; false when the thread
// could not be made.
inline bool run_on_small_stack(const std::function<void()>& fn, std::size_t stack_bytes = kSmallStackBytes) {
  pthread_attr_t attr;
  if (pthread_attr_init(&attr) != 0) return false;
  bool ok = pthread_attr_setstacksize(&attr, stack_bytes) == 0;
  pthread_t thread{};
  auto body = [](void* arg) -> void* {
    (*static_cast<const std::function<void()>*>(arg))();
    return nullptr;
  };
  ok = ok && pthread_create(&thread, &attr, body, const_cast<std::function<void()>*>(&fn)) == 0;
  pthread_attr_destroy(&attr);
  if (ok) pthread_join(thread, nullptr);
  return ok;
}

}  // namespace symb::test_support
