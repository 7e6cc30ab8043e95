// FrameSequence: what the receiver of numbered frames on a serial line checks (docs/hil.md): a
// sequence number not newer than the last is out of order (dropped); numbers skipped are missed
// frames; seq 0 after others is a sender that started anew; no frame for `lost_after` is a lost
// link, and the next frame brings it back. A pure state machine: the caller owns the time, the
// counters and the log; here only the decision and the log line's words, so that every receiver
// (the Linux board's `ir` task, the Cortex-M board's) says the same thing the same way.
#pragma once

#include <cstdint>
#include <string>

#include "symb/kernel/time.hpp"

namespace symb::io {

struct SequenceStep {
  bool accepted = false;     // false: out of order, dropped
  std::uint64_t missed = 0;  // sequence numbers skipped before this one
  bool restart = false;      // seq 0 after others
  bool recovered = false;    // the first frame after a lost link
  // Info lines to log, in order, for an accepted frame (restart, then link up or back); empty when
  // none. For a refused frame: the out-of-order line's tail ("seq 5 after 7").
  std::string note_restart, note_link, out_of_order;
};

class FrameSequence {
 public:
  // `frame` names the frames in the log lines ("IR frame", "sensor frame").
  explicit FrameSequence(kernel::Duration lost_after, std::string frame = "IR frame")
      : lost_after_(lost_after), frame_(std::move(frame)) {}

  // The receiver started at `t` (a link silent from here on is lost after lost_after).
  void start(kernel::Time t) { last_frame_ = t; }
  // A frame numbered `seq` arrived at `t`.
  SequenceStep on_frame(std::uint32_t seq, kernel::Time t);
  // At a tick: true once per silence, when the link was up and no frame came for lost_after; the
  // log line is then lost_note(t).
  bool lost(kernel::Time t);
  std::string lost_note(kernel::Time t) const;

  std::uint32_t last_seq() const { return last_seq_; }
  bool up() const { return up_; }

 private:
  kernel::Duration lost_after_;
  std::string frame_;
  kernel::Time last_frame_{0};
  std::uint32_t last_seq_ = 0;
  bool have_seq_ = false;
  bool up_ = false;
  bool ever_up_ = false;
};

}  // namespace symb::io
