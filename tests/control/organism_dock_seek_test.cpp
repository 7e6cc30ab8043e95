// The self-assembly seeker's steering (DockSeeker) phase by phase on synthetic beacon, IR and gyro
// readings: search without a beacon, approach the pre-dock point, align face to face, dock in,
// latch only when aligned, close and face to face, back off from another seeker ahead or when
// stuck, stop once docked; and the wheel mix that never exceeds the top speed.
#include <cmath>

#include <gtest/gtest.h>

#include "symb/control/organism/dock_seek_task.hpp"

namespace symb::control::organism {
namespace {

using namespace std::chrono_literals;
constexpr double kSeekDt = 0.03;

SeekInput seek_beacon(double d, double bearing, double heading, double gyro = 0.5) {
  SeekInput in;
  in.distance = d;
  in.bearing = bearing;
  in.heading = heading;
  in.gyro_z = gyro;
  return in;
}

TEST(DockSeeker, WithoutABeaconItSpinsOnTheSpotThenDrivesOnWithTheDrawnTurn) {
  DockSeekOptions o;
  o.search_spin = 1s;
  o.search_drive = 1s;
  DockSeeker s(o);
  SeekInput none;
  none.gyro_z = 1;
  SeekOutput out = s.step(none, kSeekDt, 0.3);
  EXPECT_EQ(s.phase(), SeekPhase::kSearch);
  EXPECT_EQ(out.v, 0);
  EXPECT_EQ(out.w, 1.0);
  for (int i = 0; i < 40; ++i) out = s.step(none, kSeekDt, -0.7);  // 1.2 s: driving now
  EXPECT_EQ(out.v, 0.1);
  EXPECT_EQ(out.w, -0.7);  // drawn when the drive started
  for (int i = 0; i < 10; ++i) out = s.step(none, kSeekDt, 0.9);
  EXPECT_EQ(out.w, -0.7);                                         // kept for the whole drive
  for (int i = 0; i < 30; ++i) out = s.step(none, kSeekDt, 0.9);  // past 2 s: a new scan
  EXPECT_EQ(out.v, 0);
  EXPECT_EQ(out.w, 1.0);
  EXPECT_FALSE(out.latch);
}

TEST(DockSeeker, ABeaconStraightAheadOnTheTargetsNormalIsApproachedStraight) {
  DockSeeker s;
  const SeekOutput out = s.step(seek_beacon(0.8, 0, 0), kSeekDt, 0);
  EXPECT_EQ(s.phase(), SeekPhase::kApproach);
  EXPECT_NEAR(out.v, 0.12, 1e-9);  // the pre-dock point is 0.55 m ahead: full approach speed
  EXPECT_NEAR(out.w, 0, 1e-9);
}

TEST(DockSeeker, ATargetFacingSidewaysIsApproachedByWayOfItsPreDockPoint) {
  DockSeeker s;
  // Target 0.5 m ahead, its face turned to my left (its reversed normal 90 deg to my right):
  // its pre-dock point lies to my left, so I turn left.
  const SeekOutput out = s.step(seek_beacon(0.5, 0, -std::numbers::pi / 2), kSeekDt, 0);
  EXPECT_EQ(s.phase(), SeekPhase::kApproach);
  EXPECT_GT(out.w, 1.0);
}

TEST(DockSeeker, APreDockPointBehindIsReachedByTurningTowardsAFarTargetOrReversingFromANearOne) {
  DockSeeker s;
  // Target 0.5 m away, 86 deg to my right, facing the way I face: its pre-dock point lies behind
  // me. Turn on the spot to the target's side (right), and keep that side while the point is
  // behind, even when the bearing jumps to the other side.
  SeekOutput out = s.step(seek_beacon(0.5, -1.5, 0), kSeekDt, 0);
  EXPECT_EQ(s.phase(), SeekPhase::kApproach);
  EXPECT_EQ(out.v, 0);
  EXPECT_EQ(out.w, -1.5);
  out = s.step(seek_beacon(0.5, 1.6, 0), kSeekDt, 0);  // the point still behind, the target now left
  EXPECT_EQ(out.w, -1.5);
  // Target straight ahead, face to face, 5 cm away: the pre-dock point is 0.2 m behind: reverse
  // straight onto it.
  DockSeeker near;
  out = near.step(seek_beacon(0.05, 0, 0), kSeekDt, 0);
  EXPECT_LT(out.v, 0);
  EXPECT_NEAR(out.w, 0, 1e-9);
}

TEST(DockSeeker, AtThePreDockPointItAlignsThenDocksStraightIn) {
  DockSeekOptions o;
  DockSeeker s(o);
  // At the pre-dock point (0.25 m out on the normal) but turned 0.3 rad: heading -0.3 from me.
  const double d = o.predock;
  SeekOutput out = s.step(seek_beacon(d, -0.3, -0.3), kSeekDt, 0);
  EXPECT_EQ(s.phase(), SeekPhase::kAlign);
  EXPECT_EQ(out.v, 0);
  EXPECT_LT(out.w, 0);  // turns towards it
  out = s.step(seek_beacon(d, 0.01, 0.02), kSeekDt, 0);
  EXPECT_EQ(s.phase(), SeekPhase::kDock);
  EXPECT_EQ(out.v, 0.05);
  EXPECT_NEAR(out.w, 4 * 0.01 + 2 * 0.02, 1e-9);
  // Off the line by more than 4 cm: approach again.
  out = s.step(seek_beacon(0.2, 0.4, 0), kSeekDt, 0);
  EXPECT_EQ(s.phase(), SeekPhase::kApproach);
}

TEST(DockSeeker, LatchesOnlyWhenAlignedCloseAndFaceToFace) {
  DockSeeker s;
  SeekInput in = seek_beacon(0.02, 0, 0.05);
  in.state = 1;
  EXPECT_TRUE(s.step(in, kSeekDt, 0).latch);
  in.heading = 0.2;  // aligned by the world's tolerance, but maybe another seeker's connector
  EXPECT_FALSE(s.step(in, kSeekDt, 0).latch);
  in = seek_beacon(0.03, 0, 0);
  in.state = 1;
  EXPECT_FALSE(s.step(in, kSeekDt, 0).latch);
  in = seek_beacon(0.02, 0, 0);
  in.state = 0;
  EXPECT_FALSE(s.step(in, kSeekDt, 0).latch);
}

TEST(DockSeeker, SomethingNearerThanTheTargetAheadMakesItBackOffForAWhile) {
  DockSeekOptions o;
  o.backoff_time = 300ms;
  DockSeeker s(o);
  SeekInput in = seek_beacon(0.5, 0, 0);
  in.front_ir = 0.04;
  SeekOutput out = s.step(in, kSeekDt, 0);
  EXPECT_EQ(s.phase(), SeekPhase::kBackOff);
  EXPECT_LT(out.v, 0);
  in.front_ir.reset();
  for (int i = 0; i < 5; ++i) out = s.step(in, kSeekDt, 0);
  EXPECT_EQ(s.phase(), SeekPhase::kBackOff);
  for (int i = 0; i < 10; ++i) out = s.step(in, kSeekDt, 0);
  EXPECT_EQ(s.phase(), SeekPhase::kApproach);
  EXPECT_GT(out.v, 0);
  // The target itself at the IR's distance is no reason to back off.
  in = seek_beacon(0.05, 0, 0);
  in.front_ir = 0.05;
  s.step(in, kSeekDt, 0);
  EXPECT_NE(s.phase(), SeekPhase::kBackOff);
}

TEST(DockSeeker, StuckWhileCommandedMeansNeitherBeaconNorGyroMovedForTheWindow) {
  DockSeekOptions o;
  o.stuck_time = 1s;
  DockSeeker s(o);
  // The beacon stays at 0.6 m and the gyro reads 0 for more than a second: stuck.
  int steps = 0;
  while (s.phase() != SeekPhase::kBackOff && steps < 100) {
    s.step(seek_beacon(0.6, 0, 0, 0), kSeekDt, 0);
    ++steps;
  }
  EXPECT_EQ(s.phase(), SeekPhase::kBackOff);
  EXPECT_NEAR(steps * kSeekDt, 1.0, 0.05);
  // Moving towards it (the distance shrinks) is not stuck.
  DockSeeker moving(o);
  for (int i = 0; i < 100; ++i) moving.step(seek_beacon(0.9 - i * 0.003, 0, 0, 0), kSeekDt, 0);
  EXPECT_NE(moving.phase(), SeekPhase::kBackOff);
}

TEST(DockSeeker, DockedItStopsAndSeeksAgainOnlyWhenUndocked) {
  DockSeeker s;
  SeekInput in = seek_beacon(-1, 0, 0);
  in.state = 2;
  const SeekOutput out = s.step(in, kSeekDt, 0);
  EXPECT_EQ(s.phase(), SeekPhase::kDocked);
  EXPECT_EQ(out.v, 0);
  EXPECT_EQ(out.w, 0);
  in.state = 0;
  s.step(in, kSeekDt, 0);
  EXPECT_EQ(s.phase(), SeekPhase::kSearch);
}

TEST(DockSeeker, TheWheelMixKeepsTheTurnAndNeverExceedsTheTopSpeed) {
  DockSeeker s;
  const auto w = s.wheels({0.12, 3.0, false});  // 0.12 -+ 0.165: scaled down together
  EXPECT_NEAR(std::max(std::abs(w[0]), std::abs(w[1])), 0.15, 1e-12);
  EXPECT_NEAR((w[1] - w[0]) / (w[1] + w[0]), (2 * 3.0 * 0.055) / (2 * 0.12), 1e-9);
  const auto slow = s.wheels({0.05, 0.0, false});
  EXPECT_EQ(slow[0], 0.05);
  EXPECT_EQ(slow[1], 0.05);
}

}  // namespace
}  // namespace symb::control::organism
