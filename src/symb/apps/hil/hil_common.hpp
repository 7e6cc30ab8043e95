// What the hardware-in-the-loop commands (`symb link`, `symb sim`, `symb board`) share: reading a
// command line with one positional SCENARIO among options, Ctrl-C as a request to stop and
// finish cleanly, and the seed a robot's node gets (the same as in-process, so the board's
// random streams are the in-process run's).
#pragma once

#include <atomic>
#include <cstdint>
#include <mutex>
#include <ostream>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "symb/apps/cli_args.hpp"
#include "symb/apps/interrupt_flag.hpp"
#include "symb/os/syslog.hpp"

namespace symb::apps::hil {

using apps::InterruptFlag;

// Writes a node's log entries to a stream, one line each, prefixed with the node's name;
// serialised, as tasks on several threads log at once.
class PrefixedLogSink final : public os::LogSink {
 public:
  PrefixedLogSink(std::ostream& out, std::string prefix) : out_(out), prefix_(std::move(prefix)) {}
  void write(const os::LogEntry& e) override;

 private:
  std::mutex mu_;
  std::ostream& out_;
  std::string prefix_;
};

}  // namespace symb::apps::hil
