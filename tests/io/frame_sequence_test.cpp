#include "symb/io/frame_sequence.hpp"

#include <gtest/gtest.h>

namespace symb::io {
namespace {

using namespace std::chrono_literals;

TEST(FrameSequence, CountsMissedRefusesOldFramesAndReportsLossRestartAndReturn) {
  FrameSequence q(300ms);
  q.start(kernel::Time{0});
  SequenceStep s = q.on_frame(0, kernel::Time{10ms});
  EXPECT_TRUE(s.accepted);
  EXPECT_EQ(s.note_link, "link up: first IR frame, seq 0");
  s = q.on_frame(1, kernel::Time{40ms});
  EXPECT_TRUE(s.accepted);
  EXPECT_TRUE(s.note_link.empty());
  s = q.on_frame(4, kernel::Time{70ms});
  EXPECT_EQ(s.missed, 2u);
  s = q.on_frame(3, kernel::Time{80ms});
  EXPECT_FALSE(s.accepted);
  EXPECT_EQ(s.out_of_order, "seq 3 after 4");
  EXPECT_FALSE(q.lost(kernel::Time{369ms}));
  EXPECT_TRUE(q.lost(kernel::Time{370ms}));
  EXPECT_FALSE(q.lost(kernel::Time{400ms}));  // once per silence
  EXPECT_EQ(q.lost_note(kernel::Time{370ms}), "link lost: no IR frame for 300 ms (last seq 4); waiting for frames");
  s = q.on_frame(0, kernel::Time{500ms});
  EXPECT_TRUE(s.accepted && s.restart && s.recovered);
  EXPECT_EQ(s.note_restart, "seq 0 after 4: the simulator started anew");
  EXPECT_EQ(s.note_link, "link back after 430 ms without frames (seq 0)");
  EXPECT_EQ(q.last_seq(), 0u);
}

}  // namespace
}  // namespace symb::io
