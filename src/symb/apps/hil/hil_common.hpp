// What the hardware-in-the-loop commands (`symb link`, `symb sim`, `symb board`) share: reading a
// command line with one positional SCENARIO among options, Ctrl-C as a request to stop and
// finish cleanly, the seed a robot's node gets (the same as in-process, so the board's random
// streams are the in-process run's), and a board's web view.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <ostream>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "symb/apps/cli_args.hpp"
#include "symb/apps/interrupt_flag.hpp"
#include "symb/apps/view/live_view.hpp"
#include "symb/apps/view/view_request.hpp"
#include "symb/io/dds/dds_frame_stream.hpp"
#include "symb/os/node.hpp"
#include "symb/os/syslog.hpp"

namespace symb::apps::hil {

using apps::InterruptFlag;

// `--domain N`, `--prefix NAME` and `--lease D` of a 3D HIL command's `--dds` link (as `symb run
// --bus dds`'s): true when `o` is one of them, read into `options` and named in `given`; false for
// another option; an error for a bad value.
std::variant<bool, UsageError> parse_dds_option(const ParsedOption& o, io::DdsFrameOptions& options,
                                                std::string& given);

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

// `symb board --view`: the board's robot in a browser (its task graph, probes, SysLog and a shell;
// no world, which is the simulator's; no pause, the board keeps its link's pace). Made after the
// robot's node, gone before it: the page's shell sessions live on the node.
class BoardView {
 public:
  // Nothing when the request is off. The URL goes to `notice` ("view: http://...").
  static kernel::Result<BoardView> start(const view::ViewRequest& request, const std::string& robot, os::Node& node,
                                         const std::string& scenario, std::ostream& notice);
  BoardView(BoardView&&) noexcept = default;
  BoardView& operator=(BoardView&&) noexcept = default;
  ~BoardView() { stop(); }
  // Where the board's loop waits (between two polls or frames): frames for the page.
  void between() {
    if (live_) live_->between_slices();
  }
  // The last frames, then the page's sessions closed and the node's probe sink cleared.
  void stop();

 private:
  BoardView() = default;
  os::Node* node_ = nullptr;
  std::unique_ptr<view::LiveView> live_;
};

}  // namespace symb::apps::hil
