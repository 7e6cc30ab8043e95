#include "symb/sim/sim_drivers.hpp"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

namespace symb::sim {
namespace {

TEST(SimIrSensor, HasSevenRawChannelsUpToTheThymioMaximum) {
  SimIrSensor ir;
  EXPECT_EQ(ir.name(), "ir");
  ASSERT_EQ(ir.channels().size(), kIrCount);
  for (std::size_t i = 0; i < kIrCount; ++i) {
    EXPECT_EQ(ir.channels()[i].name, "ir" + std::to_string(i));
    EXPECT_EQ(ir.channels()[i].min, 0.0f);
    EXPECT_EQ(ir.channels()[i].max, static_cast<float>(kIrMax));
  }
}

TEST(SimIrSensor, ClampsOutOfRangeAndRejectsNaN) {
  SimIrSensor ir("front");
  EXPECT_EQ(ir.publish_readings(IrReadings{}, kernel::Time{1}), robot::PublishResult::kNotOpen);
  ASSERT_TRUE(ir.open());
  IrReadings r{1, 2, 3, 4, 5000, -3, 7};
  EXPECT_EQ(ir.publish_readings(r, kernel::Time{2}), robot::PublishResult::kUnheard);  // no task yet
  auto latest = ir.latest();
  ASSERT_TRUE(latest);
  EXPECT_EQ(latest->time, kernel::Time{2});
  ASSERT_EQ(latest->count, kIrCount);
  EXPECT_EQ(latest->values[0], 1.0f);
  EXPECT_EQ(latest->values[4], static_cast<float>(kIrMax));
  EXPECT_EQ(latest->values[5], 0.0f);
  EXPECT_EQ(ir.stats().clamped_values, 2u);

  r[3] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(ir.publish_readings(r, kernel::Time{3}), robot::PublishResult::kRejected);
  EXPECT_EQ(ir.latest()->time, kernel::Time{2});  // the NaN sample did not replace the last good one
  const float too_few[3] = {1, 2, 3};
  EXPECT_EQ(ir.publish(too_few, kernel::Time{4}), robot::PublishResult::kRejected);
  EXPECT_EQ(ir.stats().rejected, 2u);
}

TEST(SimWheels, ScalesThymioUnitsToCentimetresPerSecond) {
  EXPECT_DOUBLE_EQ(wheel_units_to_cm_per_s(500), kMaxWheelSpeed);
  EXPECT_DOUBLE_EQ(wheel_units_to_cm_per_s(-250), -kMaxWheelSpeed / 2);
  EXPECT_NEAR(cm_per_s_to_wheel_units(wheel_units_to_cm_per_s(123)), 123, 1e-9);

  SimWheels w;
  EXPECT_EQ(w.name(), "wheels");
  ASSERT_EQ(w.channels().size(), 2u);
  EXPECT_EQ(w.channels()[0].name, "left");
  EXPECT_EQ(w.channels()[1].name, "right");
  EXPECT_EQ(w.command().sequence, 0u);
  ASSERT_TRUE(w.open());
  const float cmd[2] = {250, -100};
  ASSERT_TRUE(w.set(cmd));
  const WheelCommand c = w.command();
  EXPECT_EQ(c.sequence, 1u);
  EXPECT_NEAR(c.left, 0.5 * kMaxWheelSpeed, 1e-6);
  EXPECT_NEAR(c.right, -0.2 * kMaxWheelSpeed, 1e-6);
}

TEST(SimWheels, ClampsToTheMotorRange) {
  SimWheels w;
  ASSERT_TRUE(w.open());
  const float cmd[2] = {900, -std::numeric_limits<float>::infinity()};
  auto clamped = w.set(cmd);
  ASSERT_TRUE(clamped);
  EXPECT_EQ(*clamped, 2u);
  EXPECT_DOUBLE_EQ(w.command().left, kMaxWheelSpeed);
  EXPECT_DOUBLE_EQ(w.command().right, -kMaxWheelSpeed);
  EXPECT_EQ(w.output(), (std::vector<float>{500, -500}));
}

TEST(SimWheels, RejectsNaNAndWrongCountsKeepingThePreviousCommand) {
  SimWheels w;
  ASSERT_TRUE(w.open());
  const float good[2] = {100, 200};
  ASSERT_TRUE(w.set(good));
  const float nan[2] = {std::numeric_limits<float>::quiet_NaN(), 0};
  auto r = w.set(nan);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().find("NaN"), std::string::npos) << r.error();
  const float one[1] = {5};
  EXPECT_FALSE(w.set(one));
  const WheelCommand c = w.command();
  EXPECT_EQ(c.sequence, 1u);
  EXPECT_NEAR(c.left, wheel_units_to_cm_per_s(100), 1e-6);
  EXPECT_NEAR(c.right, wheel_units_to_cm_per_s(200), 1e-6);
  EXPECT_EQ(w.stats().rejected, 2u);
}

TEST(SimWheels, ClosingStopsTheWheelsAndRefusesCommands) {
  SimWheels w;
  const float go[2] = {300, 300};
  EXPECT_FALSE(w.set(go));  // closed until opened
  EXPECT_EQ(w.command().sequence, 0u);
  ASSERT_TRUE(w.open());
  ASSERT_TRUE(w.set(go));
  EXPECT_GT(w.command().left, 0);
  w.close();
  EXPECT_EQ(w.command().left, 0.0);
  EXPECT_EQ(w.command().right, 0.0);
  EXPECT_FALSE(w.set(go));
  EXPECT_EQ(w.command().left, 0.0);
}

}  // namespace
}  // namespace symb::sim
