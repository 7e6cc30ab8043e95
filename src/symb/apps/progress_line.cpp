#include "symb/apps/progress_line.hpp"

#include <string>

namespace symb::apps {

ProgressLine::ProgressLine(std::ostream& out, bool enabled, bool terminal)
    : out_(out), enabled_(enabled), terminal_(terminal) {}

void ProgressLine::overwrite(std::string_view text) {
  std::string line = "\r";
  line += text;
  // Blank out what a longer previous line left behind.
  if (text.size() < drawn_width_) line.append(drawn_width_ - text.size(), ' ');
  drawn_width_ = text.size();
  out_ << line << std::flush;
}

void ProgressLine::update(double fraction, std::string_view text) {
  if (!enabled_ || finished_) return;
  if (terminal_) {
    const auto now = std::chrono::steady_clock::now();
    if (now - last_draw_ < std::chrono::milliseconds(100)) return;
    last_draw_ = now;
    overwrite(text);
    return;
  }
  // Only quarters strictly before the end: finish() writes the last line.
  if (next_quarter_ < 4 && fraction >= next_quarter_ / 4.0) {
    while (next_quarter_ < 4 && fraction >= next_quarter_ / 4.0) ++next_quarter_;
    out_ << text << '\n' << std::flush;
  }
}

void ProgressLine::finish(std::string_view text) {
  if (!enabled_ || finished_) return;
  finished_ = true;
  if (terminal_) {
    overwrite(text);
    out_ << '\n' << std::flush;
  } else {
    out_ << text << '\n' << std::flush;
  }
}

}  // namespace symb::apps
