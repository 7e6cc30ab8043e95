// The scaffold every text parser of the project shares (MDL2e, AHHS, networks, genomes, task
// graphs): where a piece of text stands, the one form of a located error, "LINE:COLUMN: message",
// the words of a line with their columns, and the nesting bound a recursive parser checks before
// it descends. Plain functions over string_views: no heap beyond the result, no exceptions, no OS
// calls, so the os and control layers can use it on a microcontroller.
//
//   auto words = kernel::split_words(line, line_number);      // "3:7: unexpected character (code 7)"
//   if (!words) return kernel::Error{words.error()};
//   for (const kernel::TextToken& w : *words)
//     if (w.text == "bad") return w.error("not here");          // "3:9: not here"
//
//   kernel::NestingBound nesting(32);
//   bool group() {
//     const auto level = nesting.enter();                       // one level deeper while in scope
//     if (!level) return fail(here, "nested too deeply");       // checked before recursing
//     return group();
//   }
#pragma once

#include <charconv>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "symb/kernel/result.hpp"

namespace symb::kernel {

// A place in a text: both 1-based; a column counts bytes.
struct TextLocation {
  std::size_t line = 1;
  std::size_t column = 1;
};

// `s` as a message quotes it: whole up to `max` bytes, else its first `max` and "..." (a token or
// reference nobody means is cut, so one bad line never floods the log).
inline std::string shortened(std::string_view s, std::size_t max) {
  return s.size() <= max ? std::string(s) : std::string(s.substr(0, max)) + "...";
}

// "LINE:COLUMN: ", the prefix of every located message.
inline std::string location_prefix(std::size_t line, std::size_t column) {
  return std::to_string(line) + ":" + std::to_string(column) + ": ";
}
inline std::string location_prefix(TextLocation at) { return location_prefix(at.line, at.column); }

// "LINE:COLUMN: message".
inline Error located_error(TextLocation at, std::string_view message) {
  return Error{location_prefix(at) + std::string(message)};
}

// A located message taken apart: "3:7: bad" -> {{3, 7}, "bad"}; a message that does not start
// with "LINE:COLUMN: " -> {nullopt, the whole message}. For a parser that embeds another (a genome
// holding an AHHS description) and moves the inner parser's locations into its own text.
struct LocatedMessage {
  std::optional<TextLocation> at;
  std::string_view message;
};
inline LocatedMessage split_location(std::string_view message) {
  const char* p = message.data();
  const char* end = p + message.size();
  TextLocation at;
  auto line = std::from_chars(p, end, at.line);
  if (line.ec != std::errc{} || line.ptr == end || *line.ptr != ':') return {std::nullopt, message};
  auto column = std::from_chars(line.ptr + 1, end, at.column);
  if (column.ec != std::errc{} || end - column.ptr < 2 || column.ptr[0] != ':' || column.ptr[1] != ' ')
    return {std::nullopt, message};
  return {at, message.substr(static_cast<std::size_t>(column.ptr + 2 - p))};
}

// A word of a text and where it starts.
struct TextToken {
  std::string_view text;
  std::size_t line = 1, column = 1;

  TextLocation location() const { return {line, column}; }
  // Just after the word: where a missing argument should have been.
  TextLocation end() const { return {line, column + text.size()}; }
  Error error(std::string_view message) const { return located_error(location(), message); }
  Error error_after(std::string_view message) const { return located_error(end(), message); }
};

// The words of one line (without its '\n'): runs of printable ASCII split by spaces, tabs and
// carriage returns; '#' ends the line (a comment). Each byte of `separators` is a one-byte word of
// its own (AHHS's ';'). Any other control byte or a byte >= 0x7f is an error at its column:
// "LINE:COLUMN: unexpected character (code N)".
inline Result<std::vector<TextToken>> split_words(std::string_view line, std::size_t line_number,
                                                  std::string_view separators = {}) {
  std::vector<TextToken> out;
  std::size_t i = 0;
  const auto separator = [&](char c) { return separators.find(c) != std::string_view::npos; };
  while (i < line.size()) {
    const auto c = static_cast<unsigned char>(line[i]);
    if (c == '#') break;
    if (c == ' ' || c == '\t' || c == '\r') {
      ++i;
      continue;
    }
    if (c < 0x20 || c >= 0x7f)
      return located_error({line_number, i + 1}, "unexpected character (code " + std::to_string(c) + ")");
    const std::size_t start = i;
    if (separator(line[i])) {
      ++i;
    } else {
      while (i < line.size()) {
        const auto d = static_cast<unsigned char>(line[i]);
        if (d <= ' ' || d >= 0x7f || d == '#' || separator(line[i])) break;
        ++i;
      }
    }
    out.push_back({line.substr(start, i - start), line_number, start + 1});
  }
  return out;
}

// Calls `fn(line, number)` for each line of `text` (without its '\n'; numbers from 1), the last
// one even when empty; stops at and returns the first failure.
template <class Fn>
Status for_each_line(std::string_view text, Fn&& fn) {
  std::size_t number = 1;
  for (;;) {
    const std::size_t nl = text.find('\n');
    if (auto st = fn(text.substr(0, nl), number); !st) return st;
    if (nl == std::string_view::npos) return {};
    text.remove_prefix(nl + 1);
    ++number;
  }
}

// A name: a letter or '_', then letters, digits and '_', at most `max_length` bytes.
inline bool is_identifier(std::string_view s, std::size_t max_length = std::string_view::npos) {
  if (s.empty() || s.size() > max_length) return false;
  const auto alpha = [](char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; };
  if (!alpha(s[0])) return false;
  for (char c : s)
    if (!alpha(c) && !(c >= '0' && c <= '9')) return false;
  return true;
}

// The shortest text that reads back to exactly `v` (std::to_chars): the form every text writer of
// the project (genomes, descriptions) uses, so that parse(to_text(x)) == x.
template <class Real>
std::string shortest_text(Real v) {
  char buf[64];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  return ec == std::errc() ? std::string(buf, end) : std::string("0");  // 64 characters hold any double
}

// How deep a recursive parser or compiler may go. Each recursive step holds a Level while it is
// inside; a Level that is past the bound converts to false, and the caller reports a located
// error instead of descending, so the native stack holds at most `limit` frames of that step
// whatever the input. Bounds are set far below what an 8 MiB thread stack (the executors' and the
// main thread's) needs even with ASan's larger frames.
class NestingBound {
 public:
  explicit NestingBound(int limit) : limit_(limit) {}
  NestingBound(const NestingBound&) = delete;
  NestingBound& operator=(const NestingBound&) = delete;

  class [[nodiscard]] Level {
   public:
    explicit Level(NestingBound& b) : b_(b) { ++b_.depth_; }
    ~Level() { --b_.depth_; }
    Level(const Level&) = delete;
    Level& operator=(const Level&) = delete;
    explicit operator bool() const { return b_.depth_ <= b_.limit_; }

   private:
    NestingBound& b_;
  };

  // One level deeper for as long as the returned Level lives.
  Level enter() { return Level(*this); }
  int depth() const { return depth_; }
  int limit() const { return limit_; }

 private:
  int limit_;
  int depth_ = 0;
};

}  // namespace symb::kernel
