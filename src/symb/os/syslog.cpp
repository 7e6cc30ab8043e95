#include "symb/os/syslog.hpp"

#include <algorithm>
#include <charconv>
#include <cstdio>

namespace symb::os {

const char* to_string(LogLevel l) {
  switch (l) {
    case LogLevel::kDebug: return "DEBUG";
    case LogLevel::kInfo: return "INFO";
    case LogLevel::kWarn: return "WARN";
    case LogLevel::kError: return "ERROR";
  }
  return "?";
}

namespace {
// printf's %<width>lld (pad ' ') or %0<width>lld (pad '0') of `v`.
void append_padded(std::string& out, std::int64_t v, int width, char pad) {
  char digits[24];
  const std::uint64_t magnitude = v < 0 ? 0 - static_cast<std::uint64_t>(v) : static_cast<std::uint64_t>(v);
  const auto r = std::to_chars(digits, digits + sizeof digits, magnitude);
  const int n = static_cast<int>(r.ptr - digits) + (v < 0 ? 1 : 0);
  if (pad == ' ') out.append(static_cast<std::size_t>(std::max(width - n, 0)), ' ');
  if (v < 0) out.push_back('-');
  if (pad == '0') out.append(static_cast<std::size_t>(std::max(width - n, 0)), '0');
  out.append(digits, r.ptr);
}
}  // namespace

std::string format_seconds(kernel::Time t, int width) {
  const std::int64_t us = t.count() / 1000;
  std::string out;
  append_padded(out, us / 1'000'000, width, ' ');
  out.push_back('.');
  append_padded(out, us % 1'000'000, 6, '0');
  return out;
}

std::string format_log_entry(const LogEntry& e) {
  char level[16];
  std::snprintf(level, sizeof level, " %-5s ", to_string(e.level));
  std::string line = "[" + format_seconds(e.time, 6) + "]" + level;
  line += e.source;
  line += ": ";
  line += e.text;
  return line;
}

SysLog::SysLog(const kernel::Clock& clock, std::size_t capacity)
    : clock_(clock), capacity_(std::max<std::size_t>(capacity, 1)) {}

void SysLog::write(LogLevel level, std::string_view source, std::string_view text) {
  std::lock_guard lock(mu_);
  if (level < level_) return;
  LogEntry e;
  e.seq = next_seq_++;
  e.time = clock_.now();
  e.level = level;
  e.source = std::string(source.substr(0, 64));
  e.text = std::string(text.substr(0, kMaxText));
  // Control characters would let a log line forge another; show them as '?'.
  for (char& c : e.text)
    if (static_cast<unsigned char>(c) < 0x20 && c != '\t') c = '?';
  for (const auto& s : sinks_) s->write(e);
  if (ring_.size() == capacity_) {
    ring_.pop_front();
    ++overwritten_;
  }
  ring_.push_back(std::move(e));
}

void SysLog::set_level(LogLevel level) {
  std::lock_guard lock(mu_);
  level_ = level;
}

LogLevel SysLog::level() const {
  std::lock_guard lock(mu_);
  return level_;
}

std::vector<LogEntry> SysLog::since(std::uint64_t after, std::size_t max) const {
  std::lock_guard lock(mu_);
  std::vector<LogEntry> out;
  auto it =
      std::upper_bound(ring_.begin(), ring_.end(), after, [](std::uint64_t s, const LogEntry& e) { return s < e.seq; });
  for (; it != ring_.end() && out.size() < max; ++it) out.push_back(*it);
  return out;
}

std::uint64_t SysLog::last_seq() const {
  std::lock_guard lock(mu_);
  return next_seq_ - 1;
}

std::uint64_t SysLog::overwritten() const {
  std::lock_guard lock(mu_);
  return overwritten_;
}

void SysLog::add_sink(std::shared_ptr<LogSink> sink) {
  std::lock_guard lock(mu_);
  sinks_.push_back(std::move(sink));
}

void SysLog::remove_sink(const std::shared_ptr<LogSink>& sink) {
  std::lock_guard lock(mu_);
  std::erase(sinks_, sink);
}

}  // namespace symb::os
