// BoardLink: the board side of a hardware-in-the-loop pair (paper V-A, docs/hil.md). It makes a
// robot's two device tasks talk to a simulator over a serial line instead of simulated drivers,
// so the board runs exactly the graph the paper's Fig. 3 shows:
//
//   link (StreamTask, frames) -> ir -> [controller tasks from the scenario] -> wheels -> link
//
//   link    the serial port in frames mode (the paper's UART0IOStreamTask); bad frames are
//           counted by its decoder and dropped
//   ir      decodes IR frames [seq, 7 values] and sends the 7 values (clamped into [0, kIrMax])
//           on port 0, as the in-process `ir` sensor task does (the paper's PlayerSensorTask).
//           It counts malformed, out-of-order and missed frames; when no frame came for
//           `lost_periods` control periods it logs that the link is lost, and when frames come
//           back it logs that and goes on. A frame with seq 0 starts a new run (a simulator that
//           started or restarted).
//           When the device goes away (end of stream, I/O errors: a USB adapter pulled, the
//           other end of a pseudo-terminal closed) the link logs it, reopens the same path with
//           backoff (reopen_first, doubling up to reopen_most), and logs the reopening; frames
//           given to it meanwhile are counted unsent, never sent.
//   wheels  takes [left, right] in Thymio motor units from the controller, rejects NaN and wrong
//           counts, clamps to +-500 and sends [seq, left, right] to `link`, seq being the newest
//           IR frame `ir` passed on (the paper's PlayerActuatorTask). Its watchdog is the
//           in-process actuator_sink's: no command for 1.5 control periods sends [seq, 0, 0] once.
//
// Use: make a BoardLink over an open (or openable) stream and pass make_device_tasks() as
// RobotSystemOptions::make_device_tasks. The three tasks are made in code (type "-"): their
// devices are not a registry's to hand out. ir and wheels declare the in-process device tasks'
// layouts (device_task_ports), so the board refuses the same hooks a simulated robot does. stats() may be read from any
// thread.
//
// The node keeps the wall clock (the paper's board, on OS threads): it shows how the control
// system copes with real time. HilRobotBoard (hil_robot_board.hpp) is the same robot on a clock
// the simulator's frames drive, which is the in-process run bit for bit.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>

#include "symb/io/frame_codec.hpp"
#include "symb/io/stream.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"
#include "symb/os/node.hpp"

namespace symb::sim {

inline constexpr std::string_view kLinkTaskName = "link";

struct BoardLinkOptions {
  kernel::Duration control_period = std::chrono::milliseconds(30);
  // The link counts as lost after this many control periods without an IR frame.
  int lost_periods = 10;
  // The wheels watchdog: stop after this many control periods without a command (as in-process).
  double watchdog_periods = 1.5;
  kernel::Duration warn_interval = std::chrono::seconds(1);
  // A serial line that went away (a pulled USB adapter, a pseudo-terminal closed) is reopened by
  // its path: at once, then after reopen_first, doubling up to reopen_most (io::ReopenBackoff).
  kernel::Duration reopen_first = std::chrono::milliseconds(100);
  kernel::Duration reopen_most = std::chrono::seconds(2);
};

struct BoardLinkStats {
  // The serial line (the link task's stream and frame decoder), refreshed once per control
  // period and whenever a frame arrives.
  std::uint64_t bytes_in = 0;
  std::uint64_t bytes_out = 0;
  std::uint64_t write_errors = 0;
  io::FrameStats decoder;  // frames: good frames; dropped(): bad ones
  // The serial line itself (the device, not the frames on it): written + unsent == the wheel
  // frames the link was given; a frame is never counted sent into a line that is down.
  std::uint64_t frames_written = 0;  // wheel frames the line took
  std::uint64_t frames_unsent = 0;   // wheel frames dropped: the line was down or refused them
  std::uint64_t line_losses = 0;     // times the device went away
  std::uint64_t line_reopens = 0;    // times it was opened again
  kernel::Duration line_down{0};     // time down in all, the outage in progress included
  bool line_open = false;
  // The ir task.
  std::uint64_t ir_frames = 0;     // IR frames passed on to the controller
  std::uint64_t malformed = 0;     // good frames that are not IR frames (count, sequence, NaN)
  std::uint64_t out_of_order = 0;  // sequence not newer than the last one: dropped
  std::uint64_t missed = 0;        // sequence numbers skipped (lost or corrupted frames, stale below)
  std::uint64_t restarts = 0;      // frames with seq 0 after others: the simulator started anew
  std::uint64_t clamped = 0;       // IR values moved into [0, kIrMax]
  // Frames pushed out of the ir task's queue unhandled by newer ones: the board fell behind (a
  // starved process) and sensor data keeps the newest. Each is also a skipped sequence number, so
  // missed = corrupted + stale + lost on the line. Refreshed at every control period and at stop.
  std::uint64_t stale = 0;
  std::uint64_t link_losses = 0;
  std::uint64_t link_recoveries = 0;
  bool link_up = false;
  std::uint32_t last_seq = 0;
  // The wheels task.
  std::uint64_t wheel_commands = 0;  // commands sent on to the link
  std::uint64_t wheel_rejected = 0;  // NaN, wrong count or a blob: nothing sent
  std::uint64_t wheel_clamped = 0;   // values clamped to +-500
  std::uint64_t watchdog_stops = 0;  // [seq, 0, 0] sent after silence

  // Every frame that arrived and could not be used as an IR frame: CRC, framing, version and
  // size errors, and malformed payloads.
  std::uint64_t bad_frames() const { return decoder.dropped() + malformed; }
};

class BoardLink : public std::enable_shared_from_this<BoardLink> {
 public:
  static std::shared_ptr<BoardLink> create(std::shared_ptr<io::IOStream> port, BoardLinkOptions options = {});

  // Creates `link`, `ir` and `wheels` on `node`, hooks link -> ir and wheels -> link and starts
  // them (ir and wheels tick at the control period). The link task opens the port if needed.
  kernel::Status make_device_tasks(os::Node& node);
  // The same, as a RobotSystemOptions::make_device_tasks (it keeps this link alive).
  std::function<kernel::Status(os::Node&)> device_tasks();

  BoardLinkStats stats() const;
  const BoardLinkOptions& options() const { return options_; }
  io::IOStream& port() { return *port_; }

  // Internal: the state the three tasks share (public so the tasks in the .cpp can name it).
  struct Shared {
    mutable std::mutex mu;
    BoardLinkStats stats;
  };

 private:
  BoardLink(std::shared_ptr<io::IOStream> port, BoardLinkOptions options);
  std::shared_ptr<io::IOStream> port_;
  BoardLinkOptions options_;
  std::shared_ptr<Shared> shared_;
};

// "frames 1234 good, 3 bad (crc 3), ...; wheels 1230 commands, ...; frames 1230 sent, 0 not sent;
// serial line open (0 lost, 0 reopened, down 0 ms in all)"
std::string describe(const BoardLinkStats& s);

}  // namespace symb::sim
