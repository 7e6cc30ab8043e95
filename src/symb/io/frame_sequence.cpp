#include "symb/io/frame_sequence.hpp"

namespace symb::io {

SequenceStep FrameSequence::on_frame(std::uint32_t seq, kernel::Time t) {
  SequenceStep s;
  if (seq == 0) {
    s.restart = have_seq_ && last_seq_ != 0;
  } else if (have_seq_ && seq <= last_seq_) {
    s.out_of_order = "seq " + std::to_string(seq) + " after " + std::to_string(last_seq_);
    return s;
  } else if (have_seq_) {
    s.missed = seq - last_seq_ - 1;
  }
  s.accepted = true;
  if (s.restart) s.note_restart = "seq 0 after " + std::to_string(last_seq_) + ": the simulator started anew";
  if (!up_) {
    if (ever_up_)
      s.note_link = "link back after " + std::to_string(kernel::to_milliseconds(t - last_frame_)) +
                    " ms without frames (seq " + std::to_string(seq) + ")";
    else
      s.note_link = "link up: first " + frame_ + ", seq " + std::to_string(seq);
  }
  s.recovered = !up_ && ever_up_;
  up_ = ever_up_ = true;
  have_seq_ = true;
  last_seq_ = seq;
  last_frame_ = t;
  return s;
}

bool FrameSequence::lost(kernel::Time t) {
  if (!up_ || t - last_frame_ < lost_after_) return false;
  up_ = false;
  return true;
}

std::string FrameSequence::lost_note(kernel::Time t) const {
  return "link lost: no " + frame_ + " for " + std::to_string(kernel::to_milliseconds(t - last_frame_)) +
         " ms (last seq " + std::to_string(last_seq_) + "); waiting for frames";
}

}  // namespace symb::io
