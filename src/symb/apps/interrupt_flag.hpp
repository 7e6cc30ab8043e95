// InterruptFlag: Ctrl-C (SIGINT) and SIGTERM as a request to stop and finish cleanly, for the
// commands that write results at the end (`symb run`, `symb sim`, `symb board`, `symb link`):
// they poll raised() between steps and write what was run instead of dying mid-file.
#pragma once

namespace symb::apps {

// While alive, SIGINT and SIGTERM set a flag instead of ending the process (a handler can reach
// only a static, which is why this flag is one: it belongs to the process, as signals do).
class InterruptFlag {
 public:
  InterruptFlag();
  ~InterruptFlag();
  InterruptFlag(const InterruptFlag&) = delete;
  InterruptFlag& operator=(const InterruptFlag&) = delete;
  bool raised() const;
};

}  // namespace symb::apps
