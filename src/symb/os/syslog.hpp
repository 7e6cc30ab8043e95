// SysLog: a node's log (the paper's SysLog class). Entries carry the node-clock time, a level and
// the source (a task name, or the node itself). Memory is bounded: the newest `capacity` entries
// are kept in a ring, each text cut at kMaxText characters, and every entry has a sequence number
// so a reader (the shell's "log follow") can ask for what came after what it saw. Sinks receive
// every entry as it is written (a terminal, a file opened by the application).
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "symb/kernel/clock.hpp"

namespace symb::os {

enum class LogLevel : std::uint8_t { kDebug, kInfo, kWarn, kError };

const char* to_string(LogLevel l);

struct LogEntry {
  std::uint64_t seq = 0;
  kernel::Time time{0};
  LogLevel level = LogLevel::kInfo;
  std::string source;
  std::string text;
};

// One line: "[   12.345678] WARN  source: text".
std::string format_log_entry(const LogEntry& e);
// `t` as seconds with six decimals, the whole seconds right-aligned in `width` ("    12.034000"
// for width 6): printf's "%*lld.%06lld" without printf, whose long long a microcontroller's
// small C library (newlib-nano, the board's) does not format.
std::string format_seconds(kernel::Time t, int width = 0);

class LogSink {
 public:
  virtual ~LogSink() = default;
  // Called with the log's lock held: keep it short, never log from here.
  virtual void write(const LogEntry& e) = 0;
};

// Writes formatted lines to a stream the caller owns (and keeps alive while the sink is added).
class OstreamLogSink final : public LogSink {
 public:
  explicit OstreamLogSink(std::ostream& out) : out_(out) {}
  void write(const LogEntry& e) override { out_ << format_log_entry(e) << '\n' << std::flush; }

 private:
  std::ostream& out_;
};

class SysLog {
 public:
  static constexpr std::size_t kMaxText = 240;

  SysLog(const kernel::Clock& clock, std::size_t capacity);

  void write(LogLevel level, std::string_view source, std::string_view text);
  void debug(std::string_view source, std::string_view text) { write(LogLevel::kDebug, source, text); }
  void info(std::string_view source, std::string_view text) { write(LogLevel::kInfo, source, text); }
  void warn(std::string_view source, std::string_view text) { write(LogLevel::kWarn, source, text); }
  void error(std::string_view source, std::string_view text) { write(LogLevel::kError, source, text); }

  // Entries below this level are neither kept nor passed to sinks.
  void set_level(LogLevel level);
  LogLevel level() const;

  // Entries with seq > after still in the ring, oldest first, at most `max`.
  std::vector<LogEntry> since(std::uint64_t after, std::size_t max = SIZE_MAX) const;
  // Sequence number of the newest entry (0 when nothing was written).
  std::uint64_t last_seq() const;
  // Entries pushed out of the ring so far.
  std::uint64_t overwritten() const;

  void add_sink(std::shared_ptr<LogSink> sink);
  void remove_sink(const std::shared_ptr<LogSink>& sink);

 private:
  const kernel::Clock& clock_;
  const std::size_t capacity_;
  mutable std::mutex mu_;
  std::deque<LogEntry> ring_;
  std::uint64_t next_seq_ = 1;
  std::uint64_t overwritten_ = 0;
  LogLevel level_ = LogLevel::kInfo;
  std::vector<std::shared_ptr<LogSink>> sinks_;
};

}  // namespace symb::os
