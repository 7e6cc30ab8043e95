// What the hardware-in-the-loop commands (`symb link`, `symb sim`, `symb board`) share: reading a
// command line with one positional SCENARIO among options, Ctrl-C as a request to stop and
// finish cleanly, the seed a robot's node gets (the same as in-process, so the board's random
// streams are the in-process run's), a board's web view, and the run of a board whose node's
// clock the simulator's frames drive.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
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
#include "symb/io/reopen_backoff.hpp"
#include "symb/io/stream.hpp"
#include "symb/kernel/clock.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/os/syslog.hpp"
#include "symb/sim/frame_clock_board.hpp"

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

// A board whose node runs on the simulator's frames (a 3D module; a 2D robot with `--lockstep`),
// run from its built node to its end: the node's log printed as it comes (unless quiet), its shell
// on `shell_port` (the board's devices, uart0 the data line, uart1 the shell line), the clock
// started, the web view, a line saying where it runs, then the loop until Ctrl-C, the duration or a
// message cycle: serve the line, run what the shell injected, give the view its frames, print the
// statistics every `stats_every`. A serial line that goes away is reopened by its path with
// backoff (100 ms doubling to 2 s), as the board on the wall clock does; what happened goes to
// ctx.err, each line prefixed with "board NAME: ".
struct FrameBoardRun {
  sim::FrameClockBoard* board = nullptr;
  kernel::VirtualTimeExecutor* executor = nullptr;   // the node's, which the board drives
  os::Node* node = nullptr;                          // its cycle_error() ends the loop
  std::vector<std::shared_ptr<io::Device>> devices;  // the board's, for the shell's table
  std::string what = "robot";                        // "robot" or "module", for the person
  std::string robot, scenario, where;                // names, and where the data line is
  std::shared_ptr<io::IOStream> data;                // the data line (the shell's uart0)
  // Whether `data` is a serial line to reopen when serve() fails; if not (a DDS stream), `gone`
  // decides: false ends the loop, true waits on.
  bool reopen = true;
  std::function<bool(const std::string& error)> gone;
  std::shared_ptr<io::IOStream> shell_port;  // may be null
  std::string shell_path;
  bool quiet = false;
  view::ViewRequest view;
  std::function<std::string()> stats;  // "frames 12 good, ..." for the periodic line
  std::optional<kernel::Duration> duration;
  kernel::Duration stats_every = std::chrono::seconds(5);
};

struct FrameBoardEnd {
  std::string cycle;       // the message cycle that ended the loop, or empty
  io::ReopenBackoff line;  // the line's losses, reopenings and time down
  kernel::Time at{0};      // the loop's end, on the clock `line` was kept on: down_for(at)
};

// Fails, before the loop, when the shell, the clock or the view cannot start.
kernel::Result<FrameBoardEnd> run_frame_board(const FrameBoardRun& run, const CliContext& ctx);

// The last line of such a board: "board-stats: good=N bad=N missed=N ... line_open=1", the
// board's books and its line's; `extra` (" docking=2") goes after the answers.
std::string frame_board_stats_line(const sim::FrameClockStats& s, const FrameBoardEnd& end,
                                   const std::string& extra = {});
// Empty, or why the run failed at its end: a message cycle, or a dead link (the serial line
// `serial` down when the board stopped, with how long and how often).
std::string frame_board_failure(const FrameBoardEnd& end, const std::string& serial);

}  // namespace symb::apps::hil
