// SYMB_SKIP_UNDER_TSAN: the first statement of a test that is one long virtual-time run. Such a
// run is single-threaded, so ThreadSanitizer has nothing to find in it, and it costs minutes
// under TSan; the release and ASan builds still run it.
#pragma once

#include <gtest/gtest.h>

#ifdef SYMB_TSAN
#define SYMB_SKIP_UNDER_TSAN() \
  GTEST_SKIP() << "one long virtual-time run on one thread: nothing for ThreadSanitizer (release and ASan run it)"
#else
#define SYMB_SKIP_UNDER_TSAN() static_cast<void>(0)
#endif
