// The board's end of the hardware-in-the-loop line (docs/hil.md, docs/board.md): the three device
// tasks of `symb board` (src/symb/sim/board_link.hpp), with the same frames, the same checks and
// counters and the same log lines, but no heap on the message path: frames are decoded into and
// encoded from fixed buffers, and numbers travel inline in messages.
//
//   link    reads the data UART (every tick, 1 ms), decodes frames; a number frame of 8 values
//           goes to `ir` as [seq, ir0..ir6]; any other good frame is malformed; bad frames are
//           counted by the decoder. Wheel commands [seq, left, right] from `wheels` are written.
//   ir      sequence checks (missed, out of order, restart at seq 0), lost/back link reports
//           (io::FrameSequence, as the Linux board's), clamps into [0, 4505], sends the 7 values.
//   wheels  refuses NaN and wrong counts, clamps to +-500, sends [seq, left, right] to `link`;
//           its watchdog sends [seq, 0, 0] once after 1.5 control periods without a command.
#pragma once

#include <array>
#include <cstdint>
#include <memory>

#include "symb/io/frame_codec.hpp"
#include "symb/io/stream.hpp"
#include "symb/kernel/result.hpp"
#include "symb/os/node.hpp"

namespace symb::board {

// The counters `symb board` prints in its board-stats line (sim::BoardLinkStats' names).
struct HilStats {
  std::uint64_t ir_frames = 0;
  std::uint64_t malformed = 0;
  std::uint64_t out_of_order = 0;
  std::uint64_t missed = 0;
  std::uint64_t restarts = 0;
  std::uint64_t clamped = 0;
  std::uint64_t link_losses = 0;
  std::uint64_t link_recoveries = 0;
  bool link_up = false;
  std::uint32_t last_seq = 0;
  std::uint64_t wheel_commands = 0;
  std::uint64_t wheel_rejected = 0;
  std::uint64_t wheel_clamped = 0;
  std::uint64_t watchdog_stops = 0;
  std::uint64_t frames_written = 0;
  std::uint64_t frames_unsent = 0;
  io::FrameStats decoder;
  std::uint64_t bad_frames() const { return decoder.dropped() + malformed; }
};

struct HilOptions {
  kernel::Duration control_period = std::chrono::milliseconds(30);
  int lost_periods = 10;
  double watchdog_periods = 1.5;
  kernel::Duration poll = std::chrono::milliseconds(1);
};

// Creates link, ir and wheels on `node` over `port` and hooks link -> ir and wheels -> link.
// `stats` must outlive the tasks.
kernel::Status make_hil_tasks(os::Node& node, std::shared_ptr<io::IOStream> port, HilStats& stats,
                              const HilOptions& options = {});

// "board-stats: good=... bad=..." as `symb board` prints it.
void format_board_stats(const HilStats& s, char* out, std::size_t size);

}  // namespace symb::board
