// ProgressLine: how a long run tells a person it is alive. On a terminal it keeps one status line
// up to date in place (\r, at most ten times a second); into a file or a pipe, where \r makes a
// mess, it writes a plain line at each quarter instead. It reads the wall clock, which is fine
// here: it is the application watching a run, not task code.
#pragma once

#include <chrono>
#include <ostream>
#include <string_view>

namespace symb::apps {

class ProgressLine {
 public:
  // Writes nothing at all when `enabled` is false. `terminal`: whether `out` is a TTY.
  ProgressLine(std::ostream& out, bool enabled, bool terminal);

  // `fraction` of the work is done (0..1); `text` describes the state.
  void update(double fraction, std::string_view text);
  // The last state; ends the line.
  void finish(std::string_view text);

 private:
  void overwrite(std::string_view text);

  std::ostream& out_;
  bool enabled_;
  bool terminal_;
  std::chrono::steady_clock::time_point last_draw_{};
  std::size_t drawn_width_ = 0;
  int next_quarter_ = 1;
  bool finished_ = false;
};

}  // namespace symb::apps
