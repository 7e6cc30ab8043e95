#include "symb/robot/channel_spec.hpp"

#include <array>
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "symb/os/warning_limiter.hpp"
#include "symb/robot/drive_goal.hpp"

namespace symb::robot {
namespace {

using namespace std::chrono_literals;

const std::vector<ChannelSpec> kTwo = {{"ir0", "raw", 0, 1023}, {"ir1", "raw", 0, 1023}};

TEST(ChannelSpec, ClampsOutOfRangeAndInfinitiesButLeavesNaN) {
  const ChannelSpec c{"speed", "m/s", -0.5f, 0.5f};
  EXPECT_EQ(c.clamp(0.25f), 0.25f);
  EXPECT_EQ(c.clamp(2.0f), 0.5f);
  EXPECT_EQ(c.clamp(-std::numeric_limits<float>::infinity()), -0.5f);
  EXPECT_TRUE(std::isnan(c.clamp(std::numeric_limits<float>::quiet_NaN())));
  EXPECT_TRUE(c.contains(-0.5f));
  EXPECT_FALSE(c.contains(0.51f));
  EXPECT_EQ(describe(c), "speed [-0.5, 0.5] m/s");
}

TEST(ChannelSpec, ValidatesChannelLists) {
  EXPECT_TRUE(validate_channels(kTwo));
  EXPECT_FALSE(validate_channels({}));
  const std::vector<ChannelSpec> inverted = {{"a", "", 1, 0}};
  EXPECT_NE(validate_channels(inverted).error().find("min is above max"), std::string::npos);
  const std::vector<ChannelSpec> twice = {{"a", "", 0, 1}, {"a", "", 0, 1}};
  EXPECT_NE(validate_channels(twice).error().find("used twice"), std::string::npos);
  const std::vector<ChannelSpec> nan = {{"a", "", std::numeric_limits<float>::quiet_NaN(), 1}};
  EXPECT_FALSE(validate_channels(nan));
  const std::vector<ChannelSpec> bad_name = {{"1a", "", 0, 1}};
  EXPECT_FALSE(validate_channels(bad_name));
  std::vector<ChannelSpec> many(33);
  for (std::size_t i = 0; i < many.size(); ++i) many[i] = {"c" + std::to_string(i), "", 0, 1};
  EXPECT_NE(validate_channels(many).error().find("at most 32"), std::string::npos);
}

TEST(ChannelSpec, ConditionsSamplesAndCountsClamps) {
  std::array<float, 2> out{7, 7};
  const std::array<float, 2> in{-5, 2000};
  const Conditioned c = condition_sample(kTwo, in, out);
  EXPECT_TRUE(c.ok());
  EXPECT_EQ(c.clamped, 2u);
  EXPECT_EQ(out, (std::array<float, 2>{0, 1023}));
}

TEST(ChannelSpec, RejectsNaNAndWrongCountsWithoutTouchingTheOutput) {
  std::array<float, 2> out{7, 7};
  const std::array<float, 2> nan{5, std::numeric_limits<float>::quiet_NaN()};
  Conditioned c = condition_sample(kTwo, nan, out);
  EXPECT_EQ(c.fault, SampleFault::kNotANumber);
  EXPECT_EQ(c.channel, 1u);
  EXPECT_EQ(out, (std::array<float, 2>{7, 7}));
  const std::array<float, 1> one{5};
  c = condition_sample(kTwo, one, out);
  EXPECT_EQ(c.fault, SampleFault::kWrongCount);
  EXPECT_EQ(out, (std::array<float, 2>{7, 7}));
}

TEST(ChannelSpec, RangeOverridesForAllOrEachChannel) {
  auto all = apply_ranges(kTwo, "0:100");
  ASSERT_TRUE(all);
  EXPECT_EQ((*all)[1].max, 100.0f);
  EXPECT_EQ((*all)[1].name, "ir1");
  auto each = apply_ranges(kTwo, "0:10,-1.5:2e3");
  ASSERT_TRUE(each);
  EXPECT_EQ((*each)[0].max, 10.0f);
  EXPECT_EQ((*each)[1].min, -1.5f);
  EXPECT_EQ((*each)[1].max, 2000.0f);
  auto same = apply_ranges(kTwo, "");
  ASSERT_TRUE(same);
  EXPECT_EQ((*same)[0].max, 1023.0f);
}

TEST(ChannelSpec, RangeOverrideErrorsGiveTheColumn) {
  EXPECT_EQ(apply_ranges(kTwo, "0;1").error(), "column 2: expected ':' between the bounds (lo:hi)");
  EXPECT_EQ(apply_ranges(kTwo, "0:1,x:2").error(), "column 5: expected a finite number for a lower bound");
  EXPECT_EQ(apply_ranges(kTwo, "5:1").error(), "column 1: lower bound above upper bound");
  EXPECT_EQ(apply_ranges(kTwo, "0:nan").error(), "column 3: expected a finite number for an upper bound");
  EXPECT_NE(apply_ranges(kTwo, "0:1,0:1,0:1").error().find("3 ranges for 2 channels"), std::string::npos);
  EXPECT_EQ(apply_ranges(kTwo, "0:1 ").error(), "column 4: expected ',' between ranges");
}

TEST(WarningLimiter, LetsTheFirstThroughThenOnePerIntervalWithCounts) {
  os::WarningLimiter w(1s);
  EXPECT_TRUE(w.note(kernel::Time{0}));
  EXPECT_EQ(w.count(), 1u);
  EXPECT_FALSE(w.note(kernel::Time{500ms}));
  EXPECT_FALSE(w.note(kernel::Time{900ms}, 3));
  EXPECT_TRUE(w.note(kernel::Time{1s}));
  EXPECT_EQ(w.count(), 5u);  // this one and the four held back
  EXPECT_FALSE(w.note(kernel::Time{1500ms}));
}

TEST(DriveGoal, EncodesAndDecodesGoalsAndStatuses) {
  const DriveGoal g = DriveGoal::turn(-1.5, 0.2, 42);
  auto back = decode_goal(encode_goal(g).numbers());
  ASSERT_TRUE(back);
  EXPECT_EQ(back->kind, GoalKind::kTurn);
  EXPECT_FLOAT_EQ(static_cast<float>(back->value), -1.5f);
  EXPECT_FLOAT_EQ(static_cast<float>(back->speed), 0.2f);
  EXPECT_EQ(back->id, 42u);
  const GoalStatus s{GoalEvent::kAborted, 7, GoalKind::kDrive, 0.25, GoalReason::kReplaced};
  auto sb = decode_status(encode_status(s).numbers());
  ASSERT_TRUE(sb);
  EXPECT_EQ(sb->event, GoalEvent::kAborted);
  EXPECT_EQ(sb->id, 7u);
  EXPECT_EQ(sb->reason, GoalReason::kReplaced);
  EXPECT_DOUBLE_EQ(sb->achieved, 0.25);
}

TEST(DriveGoal, RejectsMalformedGoals) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(decode_goal(std::vector<float>{}));
  EXPECT_FALSE(decode_goal(std::vector<float>{7, 1, 1}));
  EXPECT_FALSE(decode_goal(std::vector<float>{1.5f, 1, 1}));
  EXPECT_FALSE(decode_goal(std::vector<float>{1, 1}));  // drive without a speed
  EXPECT_FALSE(decode_goal(std::vector<float>{1, nan, 1}));
  EXPECT_FALSE(decode_goal(std::vector<float>{2, 1, std::numeric_limits<float>::infinity()}));
  EXPECT_FALSE(decode_goal(std::vector<float>{1, 1, 1, -1}));
  EXPECT_FALSE(decode_goal(std::vector<float>{1, 1, 1, 1.5f}));
  EXPECT_FALSE(decode_goal(std::vector<float>{1, 1, 1, 16777216.0f}));
  EXPECT_TRUE(decode_goal(std::vector<float>{0}));
  EXPECT_TRUE(decode_goal(std::vector<float>{3, -0.1f}));
  EXPECT_FALSE(decode_status(std::vector<float>{9, 1, 1, 0, 0}));
}

}  // namespace
}  // namespace symb::robot
