#include "symb/apps/hil/hil_common.hpp"

#include <algorithm>
#include <csignal>
#include <cstdio>

namespace symb::apps::hil {

namespace {

volatile std::sig_atomic_t interrupted = 0;

extern "C" void on_interrupt(int) { interrupted = 1; }

}  // namespace

InterruptFlag::InterruptFlag() {
  interrupted = 0;
  std::signal(SIGINT, on_interrupt);
  std::signal(SIGTERM, on_interrupt);
}

InterruptFlag::~InterruptFlag() {
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
}

bool InterruptFlag::raised() const { return interrupted != 0; }

void PrefixedLogSink::write(const os::LogEntry& e) {
  std::lock_guard lock(mu_);
  out_ << prefix_ << os::format_log_entry(e) << '\n' << std::flush;
}

}  // namespace symb::apps::hil
