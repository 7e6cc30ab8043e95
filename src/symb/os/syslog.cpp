#include "symb/os/syslog.hpp"

#include <algorithm>
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

std::string format_log_entry(const LogEntry& e) {
  char head[48];
  const std::int64_t us = e.time.count() / 1000;
  std::snprintf(head, sizeof head, "[%6lld.%06lld] %-5s ", static_cast<long long>(us / 1'000'000),
                static_cast<long long>(us % 1'000'000), to_string(e.level));
  std::string line(head);
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
