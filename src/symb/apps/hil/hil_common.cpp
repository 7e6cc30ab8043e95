#include "symb/apps/hil/hil_common.hpp"

#include <algorithm>
#include <cstdio>

namespace symb::apps::hil {

void PrefixedLogSink::write(const os::LogEntry& e) {
  std::lock_guard lock(mu_);
  out_ << prefix_ << os::format_log_entry(e) << '\n' << std::flush;
}

}  // namespace symb::apps::hil
