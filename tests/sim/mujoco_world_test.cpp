// The MuJoCo 3D world: docking by connectors (both sides of each tolerance, closed and docked
// connectors, a docked pair moving as one, unlatching), the hinge servo, IR per face, bit-identical
// runs and divergence reported as an error. Every figure is measured from the simulation; the
// figures written beside the bounds were measured once with this file (release build).
#include "symb/sim/mujoco/mujoco_world.hpp"

#include <cmath>
#include <cstring>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "support/measured.hpp"

namespace symb::sim::mujoco {
namespace {

constexpr double kMjMillimetre = 0.001;
constexpr double kMjDegree = std::numbers::pi / 180;
// Steps to let the modules settle on their wheels before a test measures (0.2 s).
constexpr std::uint64_t kMjSettleSteps = 100;

double mj_distance(const Vec3& a, const Vec3& b) { return std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]); }

// Two standard modules, front to front: module 0 at the origin facing +x, module 1 turned to face
// it (yaw pi + turn) with its front connector `gap` metres ahead of module 0's, then settled.
struct DockRig {
  static constexpr std::size_t kA = 0, kB = 1;
  MujocoWorld world;
  std::size_t front_a, front_b;

  static MujocoWorld make(double gap, double turn) {
    const ModuleKind kind = standard_kind();
    const double half = kind.body.size[0] / 2;
    const double yaw = std::numbers::pi + turn;
    const double cx = half + gap, cy = 0;
    auto world = MujocoWorld::make(
        {{"a", kind, {0, 0, 0}}, {"b", kind, {cx - half * std::cos(yaw), cy - half * std::sin(yaw), yaw}}});
    EXPECT_TRUE(world.ok()) << world.error();
    return std::move(world).value();
  }

  explicit DockRig(double gap, double turn = 0) : world(make(gap, turn)) {
    front_a = *world.find_connector(kA, "front");
    front_b = *world.find_connector(kB, "front");
    const auto settled = world.step(kMjSettleSteps);
    EXPECT_TRUE(settled.ok()) << settled.error();
  }

  double connector_gap() const {
    return mj_distance(world.connector_position(kA, front_a), world.connector_position(kB, front_b));
  }
  double centre_distance() const { return mj_distance(world.pose(kA).position, world.pose(kB).position); }
};

TEST(MujocoDocking, LatchesJustInsideThePositionTolerance) {
  DockRig rig(kLatchPositionTolerance - kMjMillimetre);
  EXPECT_EQ(rig.world.connector_state(DockRig::kA, rig.front_a), ConnectorState::kAligned);
  const std::size_t spare = rig.world.spare_welds_free();

  const auto latched = rig.world.latch(DockRig::kA, rig.front_a);
  ASSERT_TRUE(latched.ok()) << latched.error();
  const DockEvent& event = rig.world.docking_log().back();
  EXPECT_EQ(event.change, DockChange::kLatched);
  EXPECT_EQ(event.other_module, DockRig::kB);
  EXPECT_EQ(event.other_connector, rig.front_b);
  // Measured: 14.115 mm (each module settles 0.06 mm back from where it was put).
  EXPECT_GT(event.distance, kLatchPositionTolerance - 1.5 * kMjMillimetre);
  EXPECT_LE(event.distance, kLatchPositionTolerance);
  EXPECT_LT(event.angle, kMjDegree);
  EXPECT_EQ(rig.world.connector_state(DockRig::kA, rig.front_a), ConnectorState::kDocked);
  EXPECT_EQ(rig.world.connector_state(DockRig::kB, rig.front_b), ConnectorState::kDocked);
  const auto partner = rig.world.docked_to(DockRig::kB, rig.front_b);
  ASSERT_TRUE(partner.has_value());
  EXPECT_EQ(partner->first, DockRig::kA);
  EXPECT_EQ(partner->second, rig.front_a);
  EXPECT_EQ(rig.world.spare_welds_free(), spare - 1);
}

TEST(MujocoDocking, RefusedJustOutsideThePositionTolerance) {
  DockRig rig(kLatchPositionTolerance + kMjMillimetre);
  EXPECT_EQ(rig.world.connector_state(DockRig::kA, rig.front_a), ConnectorState::kFree);
  const std::size_t spare = rig.world.spare_welds_free();

  const auto latched = rig.world.latch(DockRig::kA, rig.front_a);
  ASSERT_FALSE(latched.ok());
  EXPECT_NE(latched.error().find("position"), std::string::npos) << latched.error();
  EXPECT_NE(latched.error().find("beyond the tolerance"), std::string::npos) << latched.error();
  const DockEvent& event = rig.world.docking_log().back();
  EXPECT_EQ(event.change, DockChange::kRefused);
  // Measured: 16.115 mm.
  EXPECT_GT(event.distance, kLatchPositionTolerance);
  EXPECT_LT(event.distance, kLatchPositionTolerance + 1.5 * kMjMillimetre);
  EXPECT_EQ(rig.world.connector_state(DockRig::kA, rig.front_a), ConnectorState::kFree);
  EXPECT_EQ(rig.world.spare_welds_free(), spare);
}

// Module b turns about its own front connector, so the connectors stay 11 mm apart (inside the
// position tolerance) and its corner clears module a's face (5 cm * sin 11 deg = 9.5 mm).
constexpr double kMjAngleGap = 0.011;

TEST(MujocoDocking, LatchesJustInsideTheAngleTolerance) {
  DockRig rig(kMjAngleGap, kLatchAngleTolerance - kMjDegree);
  const auto latched = rig.world.latch(DockRig::kA, rig.front_a);
  ASSERT_TRUE(latched.ok()) << latched.error();
  const DockEvent& event = rig.world.docking_log().back();
  EXPECT_EQ(event.change, DockChange::kLatched);
  // Measured: 9.018 deg, the connectors 11.11 mm apart.
  EXPECT_GT(event.angle, kLatchAngleTolerance - 1.5 * kMjDegree);
  EXPECT_LE(event.angle, kLatchAngleTolerance);
  EXPECT_LE(event.distance, kLatchPositionTolerance);
}

TEST(MujocoDocking, RefusedJustOutsideTheAngleTolerance) {
  DockRig rig(kMjAngleGap, kLatchAngleTolerance + kMjDegree);
  const auto latched = rig.world.latch(DockRig::kA, rig.front_a);
  ASSERT_FALSE(latched.ok());
  EXPECT_NE(latched.error().find("angle"), std::string::npos) << latched.error();
  const DockEvent& event = rig.world.docking_log().back();
  EXPECT_EQ(event.change, DockChange::kRefused);
  EXPECT_LE(event.distance, kLatchPositionTolerance);  // only the angle failed
  // Measured: 11.033 deg, the connectors 11.12 mm apart.
  EXPECT_GT(event.angle, kLatchAngleTolerance);
  EXPECT_LT(event.angle, kLatchAngleTolerance + 1.5 * kMjDegree);
}

TEST(MujocoDocking, ClosedOrAlreadyDockedConnectorsAreRefused) {
  DockRig rig(0.005);
  auto& w = rig.world;
  w.set_open(DockRig::kB, rig.front_b, false);
  auto refused = w.latch(DockRig::kA, rig.front_a);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().find("b.front, is closed"), std::string::npos) << refused.error();

  w.set_open(DockRig::kB, rig.front_b, true);
  w.set_open(DockRig::kA, rig.front_a, false);
  refused = w.latch(DockRig::kA, rig.front_a);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().find("it is closed"), std::string::npos) << refused.error();

  w.set_open(DockRig::kA, rig.front_a, true);
  ASSERT_TRUE(w.latch(DockRig::kA, rig.front_a).ok());
  for (const std::size_t module : {DockRig::kA, DockRig::kB}) {
    refused = w.latch(module, module == DockRig::kA ? rig.front_a : rig.front_b);
    ASSERT_FALSE(refused.ok());
    EXPECT_NE(refused.error().find("already docked"), std::string::npos) << refused.error();
  }
  std::vector<DockChange> changes;
  for (const auto& e : w.docking_log()) changes.push_back(e.change);
  EXPECT_EQ(changes, (std::vector<DockChange>{DockChange::kRefused, DockChange::kRefused, DockChange::kLatched,
                                              DockChange::kRefused, DockChange::kRefused}));
  EXPECT_FALSE(w.unlatch(DockRig::kA, *w.find_connector(DockRig::kA, "back")).ok());
}

// The weld is soft (time constant 5 ms); how far the docked pair may stretch or squeeze while one
// module drags the other, whose wheels brake.
constexpr double kMjWeldDriftBound = 0.0005;

TEST(MujocoDocking, DockedPairMovesAsOneBody) {
  DockRig rig(0.005);
  auto& w = rig.world;
  ASSERT_TRUE(w.latch(DockRig::kA, rig.front_a).ok());
  const double gap0 = rig.connector_gap(), centres0 = rig.centre_distance();
  const Pose3 a0 = w.pose(DockRig::kA), b0 = w.pose(DockRig::kB);
  ASSERT_TRUE(w.set_wheels(DockRig::kA, -0.1, -0.1).ok());  // a backs away, pulling b
  double drift = 0;
  for (int i = 0; i < 1000; ++i) {
    ASSERT_TRUE(w.step(1).ok());
    drift = std::max({drift, std::abs(rig.connector_gap() - gap0), std::abs(rig.centre_distance() - centres0)});
  }
  const double moved_a = w.pose(DockRig::kA).position[0] - a0.position[0];
  const double moved_b = w.pose(DockRig::kB).position[0] - b0.position[0];
  // Measured: a moved -75.905 mm and b -75.855 mm in 2 s; the largest drift was 0.059 mm.
  EXPECT_TRUE(symb::testing::near_measured(moved_b, -0.075855, 0.002));
  EXPECT_NEAR(moved_b, moved_a, kMjWeldDriftBound);
  EXPECT_LE(drift, kMjWeldDriftBound);
  EXPECT_LT(std::abs(w.pose(DockRig::kB).yaw() - b0.yaw()), kMjDegree);
}

TEST(MujocoDocking, UnlatchingPartsThePair) {
  DockRig rig(0.005);
  auto& w = rig.world;
  const std::size_t spare = w.spare_welds_free();
  ASSERT_TRUE(w.latch(DockRig::kA, rig.front_a).ok());
  ASSERT_TRUE(w.set_wheels(DockRig::kA, -0.1, -0.1).ok());
  ASSERT_TRUE(w.step(500).ok());
  const auto parted = w.unlatch(DockRig::kB, rig.front_b);  // either side may unlatch
  ASSERT_TRUE(parted.ok()) << parted.error();
  EXPECT_EQ(w.docking_log().back().change, DockChange::kUnlatched);
  // Still face to face, so aligned (latchable again) until they part.
  EXPECT_EQ(w.connector_state(DockRig::kA, rig.front_a), ConnectorState::kAligned);
  EXPECT_FALSE(w.docked_to(DockRig::kA, rig.front_a).has_value());
  EXPECT_EQ(w.spare_welds_free(), spare);
  ASSERT_TRUE(w.step(250).ok());  // b rolls out the speed it had; its wheels brake it
  const Pose3 a1 = w.pose(DockRig::kA), b1 = w.pose(DockRig::kB);
  ASSERT_TRUE(w.step(500).ok());
  const double moved_a = std::abs(w.pose(DockRig::kA).position[0] - a1.position[0]);
  const double moved_b = mj_distance(w.pose(DockRig::kB).position, b1.position);
  // Measured: a moved 85.4 mm in that second, b 0.00001 mm.
  EXPECT_GT(moved_a, 0.03);
  EXPECT_LT(moved_b, 0.0001);
  EXPECT_EQ(w.connector_state(DockRig::kA, rig.front_a), ConnectorState::kFree);
}

TEST(MujocoDocking, OneSpareWeldServesEveryPairInTurn) {
  // Three modules in a row, 5 mm apart: a faces b front to front, b's back faces c's back. One
  // spare weld: the second dock waits until the first is undone, then the same weld holds b's tail
  // to c, and c pulls b.
  constexpr double kGap = 0.005;
  const ModuleKind kind = standard_kind();
  const double length = kind.body.size[0];
  ModelOptions options;
  options.spare_welds = 1;
  auto world = MujocoWorld::make({{"a", kind, {0, 0, 0}},
                                  {"b", kind, {length + kGap, 0, std::numbers::pi}},
                                  {"c", kind, {2 * length + 2 * kGap, 0, 0}}},
                                 options);
  ASSERT_TRUE(world.ok()) << world.error();
  auto& w = world.value();
  ASSERT_TRUE(w.step(kMjSettleSteps).ok());
  const std::size_t front = *w.find_connector(0, "front"), back = *w.find_connector(1, "back");
  ASSERT_TRUE(w.latch(0, front).ok());
  auto refused = w.latch(1, back);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().find("all 1 spare welds are in use"), std::string::npos) << refused.error();
  EXPECT_EQ(w.connector_state(1, back), ConnectorState::kAligned);

  ASSERT_TRUE(w.unlatch(0, front).ok());
  const auto latched = w.latch(1, back);
  ASSERT_TRUE(latched.ok()) << latched.error();
  const auto partner = w.docked_to(1, back);
  ASSERT_TRUE(partner.has_value());
  EXPECT_EQ(partner->first, 2U);
  EXPECT_EQ(partner->second, back);
  EXPECT_EQ(w.spare_welds_free(), 0U);

  auto gap = [&] { return mj_distance(w.connector_position(1, back), w.connector_position(2, back)); };
  const double gap0 = gap();
  const Pose3 a0 = w.pose(0), b0 = w.pose(1), c0 = w.pose(2);
  ASSERT_TRUE(w.set_wheels(2, 0.1, 0.1).ok());  // c drives away from b, front first
  double drift = 0;
  for (int i = 0; i < 1000; ++i) {
    ASSERT_TRUE(w.step(1).ok());
    drift = std::max(drift, std::abs(gap() - gap0));
  }
  const double moved_b = w.pose(1).position[0] - b0.position[0];
  const double moved_c = w.pose(2).position[0] - c0.position[0];
  // Measured: c moved 98.477 mm and b 98.410 mm in 2 s (the weld holds b by its hinged tail), the
  // weld drifted 0.066 mm at most, a moved 0.0007 mm.
  EXPECT_TRUE(symb::testing::near_measured(moved_b, 0.098410, 0.002));
  EXPECT_NEAR(moved_b, moved_c, 0.005);
  EXPECT_LE(drift, kMjWeldDriftBound);
  EXPECT_LT(mj_distance(w.pose(0).position, a0.position), 0.0001);
}

TEST(MujocoDocking, SevenModuleChainHoldsOnTheSparseSolver) {
  // Seven modules in a line, each front 4 mm from the next one's back, all docked (63 degrees of
  // freedom: MuJoCo 2.2.2 switches to its sparse solver at 60, which the weld retargeting must
  // also work with). All drive forward at 0.1 m/s for 5 s while their hinges wave 0.2 rad at 1 Hz.
  constexpr std::size_t kCount = 7;
  const ModuleKind kind = standard_kind();
  std::vector<ModuleSpec> specs;
  for (std::size_t i = 0; i < kCount; ++i)
    specs.push_back({"m" + std::to_string(i), kind, {static_cast<double>(i) * (kind.body.size[0] + 0.004), 0, 0}});
  ModelOptions options;
  options.spare_welds = kCount - 1;
  auto world = MujocoWorld::make(specs, options);
  ASSERT_TRUE(world.ok()) << world.error();
  auto& w = world.value();
  ASSERT_GE(w.degrees_of_freedom(), 60U);
  ASSERT_TRUE(w.step(kMjSettleSteps).ok());
  const std::size_t front = *w.find_connector(0, "front"), back = *w.find_connector(0, "back");
  for (std::size_t i = 0; i + 1 < kCount; ++i) {
    const auto latched = w.latch(i, front);
    ASSERT_TRUE(latched.ok()) << latched.error();
    EXPECT_EQ(w.docked_to(i, front), (std::pair{i + 1, back}));
  }
  auto gap = [&](std::size_t i) {
    return mj_distance(w.connector_position(i, front), w.connector_position(i + 1, back));
  };
  std::vector<double> gaps0;
  for (std::size_t i = 0; i + 1 < kCount; ++i) gaps0.push_back(gap(i));
  const Pose3 tail0 = w.pose(0), head0 = w.pose(kCount - 1);
  for (std::size_t i = 0; i < kCount; ++i) ASSERT_TRUE(w.set_wheels(i, 0.1, 0.1).ok());
  double drift = 0;
  for (int step = 0; step < 2500; ++step) {
    for (std::size_t i = 0; i < kCount; ++i)
      w.set_hinge_target(i, 0.2 * std::sin(2 * std::numbers::pi * (w.time() - static_cast<double>(i) / kCount)));
    const auto stepped = w.step(1);
    ASSERT_TRUE(stepped.ok()) << stepped.error();
    for (std::size_t i = 0; i + 1 < kCount; ++i) drift = std::max(drift, std::abs(gap(i) - gaps0[i]));
  }
  const double moved_tail = w.pose(0).position[0] - tail0.position[0];
  const double moved_head = w.pose(kCount - 1).position[0] - head0.position[0];
  // Measured: both ends moved 493.3 mm; the largest drift of any of the six welds was 0.079 mm.
  EXPECT_TRUE(symb::testing::near_measured(moved_head, 0.4933, 0.01));
  EXPECT_NEAR(moved_tail, moved_head, 0.001);
  EXPECT_LE(drift, kMjWeldDriftBound);
}

// A fixed script: dock, drive, bend, unlatch, drive on. Returns every pose and angle on the way.
std::vector<double> mj_scripted_run() {
  DockRig rig(0.006);
  auto& w = rig.world;
  std::vector<double> trace;
  auto record = [&] {
    for (std::size_t m = 0; m < w.module_count(); ++m) {
      const Pose3 p = w.pose(m);
      trace.insert(trace.end(), p.position.begin(), p.position.end());
      trace.insert(trace.end(), p.quaternion.begin(), p.quaternion.end());
      trace.push_back(w.hinge_angle(m));
    }
  };
  EXPECT_TRUE(w.latch(DockRig::kA, rig.front_a).ok());
  EXPECT_TRUE(w.set_wheels(DockRig::kA, -0.08, -0.12).ok());
  for (int i = 0; i < 40; ++i) {
    w.set_hinge_target(DockRig::kB, 0.4 * std::sin(i * 0.3));
    EXPECT_TRUE(w.step(25).ok());
    record();
  }
  EXPECT_TRUE(w.unlatch(DockRig::kA, rig.front_a).ok());
  EXPECT_TRUE(w.set_wheels(DockRig::kB, 0.1, 0.05).ok());
  for (int i = 0; i < 20; ++i) {
    EXPECT_TRUE(w.step(25).ok());
    record();
  }
  return trace;
}

TEST(MujocoWorld, SameInputsGiveBitIdenticalRuns) {
  const std::vector<double> first = mj_scripted_run();
  const std::vector<double> second = mj_scripted_run();
  ASSERT_EQ(first.size(), second.size());
  ASSERT_FALSE(first.empty());
  EXPECT_EQ(std::memcmp(first.data(), second.data(), first.size() * sizeof(double)), 0);
  // The run did something: module a's position changed.
  EXPECT_GT(std::abs(first[first.size() - 16] - first[0]), 0.05);
}

TEST(MujocoWorld, HingeServoReachesItsTarget) {
  // Within 0.01 rad (0.6 deg) in 0.5 s, for a bend either way. Measured: +0.5 rad settles in
  // 0.434 s and ends 0.0039 rad short (it lifts the module, whose wheels' servo holds them still);
  // -0.5 rad in 0.058 s, 0.0030 short.
  constexpr double kTolerance = 0.01, kSettleBound = 0.5;
  auto world = MujocoWorld::make({{"a", standard_kind(), {0, 0, 0}}});
  ASSERT_TRUE(world.ok()) << world.error();
  auto& w = world.value();
  ASSERT_TRUE(w.step(kMjSettleSteps).ok());
  for (const double target : {0.5, -0.5}) {
    w.set_hinge_target(0, target);
    const double start = w.time();
    double last_outside = 0;
    for (int i = 0; i < 500; ++i) {
      ASSERT_TRUE(w.step(1).ok());
      if (std::abs(w.hinge_angle(0) - target) > kTolerance) last_outside = w.time() - start;
    }
    EXPECT_LE(last_outside, kSettleBound) << "target " << target;
    EXPECT_TRUE(symb::testing::near_measured(last_outside, target > 0 ? 0.434 : 0.058, 0.02)) << "target " << target;
    EXPECT_LE(std::abs(w.hinge_angle(0) - target), kTolerance) << "target " << target;
    EXPECT_LT(std::abs(w.hinge_speed(0)), 0.01) << "target " << target;
  }
}

TEST(MujocoWorld, IrSeesAModuleInFrontAndNothingWhenItIsRemoved) {
  const ModuleKind kind = standard_kind();
  const double length = kind.body.size[0];
  auto world = MujocoWorld::make({{"a", kind, {0, 0, 0}}, {"b", kind, {length + 0.05, 0, 0}}});
  ASSERT_TRUE(world.ok()) << world.error();
  auto& w = world.value();
  ASSERT_TRUE(w.step(kMjSettleSteps).ok());
  auto face_gap = [&] { return w.pose(1).position[0] - w.pose(0).position[0] - length; };
  auto seen = w.ir(0, Face::kFront);
  ASSERT_TRUE(seen.has_value());
  // Measured: 50.084 mm for a gap of 50.000 mm between the faces' centres (the settled bodies
  // lean a little, and the sensor sits 2 cm above the centre).
  EXPECT_NEAR(*seen, face_gap(), kMjMillimetre);
  EXPECT_NEAR(*seen, 0.05, 2 * kMjMillimetre);
  // Nothing behind or beside it, and its own wheels and tail do not count.
  for (const Face face : {Face::kBack, Face::kLeft, Face::kRight})
    EXPECT_FALSE(w.ir(0, face).has_value()) << face_name(face);
  const auto b_back = w.ir(1, Face::kBack);
  ASSERT_TRUE(b_back.has_value());  // b sees a behind it
  EXPECT_NEAR(*b_back, face_gap(), kMjMillimetre);

  ASSERT_TRUE(w.place(1, {1.0, 1.0, 0}).ok());
  ASSERT_TRUE(w.step(10).ok());
  EXPECT_FALSE(w.ir(0, Face::kFront).has_value());

  ASSERT_TRUE(w.place(1, {length + 0.08, 0, 0}).ok());
  ASSERT_TRUE(w.step(kMjSettleSteps).ok());
  seen = w.ir(0, Face::kFront);
  ASSERT_TRUE(seen.has_value());
  EXPECT_NEAR(*seen, face_gap(), kMjMillimetre);
  EXPECT_NEAR(*seen, 0.08, 2 * kMjMillimetre);  // measured: 80.096 mm for a gap of 80.011 mm

  ASSERT_TRUE(w.place(1, {length + kind.ir.front().range + 0.01, 0, 0}).ok());  // just out of range
  ASSERT_TRUE(w.step(10).ok());
  EXPECT_FALSE(w.ir(0, Face::kFront).has_value());
}

TEST(MujocoWorld, DivergingModelReportsAnErrorInsteadOfSpinning) {
  // A hinge servo 250 times too stiff for the 2 ms step, with no damping: Euler blows up.
  ModuleKind kind = standard_kind();
  kind.hinge.gain = 1000;
  kind.hinge.damping = 0;
  auto world = MujocoWorld::make({{"a", kind, {0, 0, 0}}});
  ASSERT_TRUE(world.ok()) << world.error();
  auto& w = world.value();
  w.set_hinge_target(0, 0.3);
  const auto stepped = w.step(5000);
  ASSERT_FALSE(stepped.ok());
  EXPECT_NE(stepped.error().find("diverged"), std::string::npos) << stepped.error();
  // Measured: MuJoCo flags it at step 5; it then resets its own clock, ours keeps counting.
  EXPECT_LT(w.steps(), 100U);
  EXPECT_GT(w.steps(), 0U);
  EXPECT_DOUBLE_EQ(w.time(), static_cast<double>(w.steps()) * kTimestep);
  EXPECT_TRUE(w.failed());
  const std::uint64_t at = w.steps();
  EXPECT_FALSE(w.step(1).ok());
  EXPECT_EQ(w.steps(), at);
  EXPECT_FALSE(w.latch(0, 0).ok());
}

TEST(MujocoModel, KindsAreData) {
  const ModuleKind cube = standard_kind(), longer = long_kind();
  EXPECT_EQ(cube.connectors.size(), 4U);
  EXPECT_EQ(cube.ir.size(), 4U);
  EXPECT_TRUE(check(cube).empty()) << check(cube);
  EXPECT_TRUE(check(longer).empty()) << check(longer);
  auto world = MujocoWorld::make({{"cube", cube, {0, 0, 0}}, {"long", longer, {0.5, 0, 0}}});
  ASSERT_TRUE(world.ok()) << world.error();
  auto& w = world.value();
  ASSERT_TRUE(w.step(kMjSettleSteps).ok());
  EXPECT_NE(w.mjcf().find("cube.wheel_l"), std::string::npos);
  EXPECT_EQ(w.mjcf().find("long.wheel_l"), std::string::npos);
  EXPECT_NEAR(w.pose(0).position[2], rest_height(cube), kMjMillimetre);
  EXPECT_NEAR(w.pose(1).position[2], rest_height(longer), kMjMillimetre);
  EXPECT_TRUE(w.set_wheels(0, 0.05, 0.05).ok());
  const auto no_wheels = w.set_wheels(1, 0.05, 0.05);
  ASSERT_FALSE(no_wheels.ok());
  EXPECT_NE(no_wheels.error().find("has no wheels"), std::string::npos);
  // Its front IR sits half its (longer) length ahead of its centre.
  const auto front = w.connector_position(1, *w.find_connector(1, "front"));
  EXPECT_NEAR(front[0] - w.pose(1).position[0], longer.body.size[0] / 2, kMjMillimetre);
}

TEST(MujocoModel, BadModulesAreRefusedWithTheReason) {
  ModuleKind bad = standard_kind();
  bad.body.mass = 0;
  bad.connectors.push_back(bad.connectors.front());
  auto world = MujocoWorld::make({{"a", bad, {0, 0, 0}}});
  ASSERT_FALSE(world.ok());
  EXPECT_NE(world.error().find("module 'a'"), std::string::npos) << world.error();
  EXPECT_NE(world.error().find("body mass"), std::string::npos) << world.error();
  EXPECT_NE(world.error().find("'front' is used twice"), std::string::npos) << world.error();

  world = MujocoWorld::make({{"a.b", standard_kind(), {0, 0, 0}}});
  ASSERT_FALSE(world.ok());
  EXPECT_NE(world.error().find("letters, digits"), std::string::npos) << world.error();
  world = MujocoWorld::make({{"a", standard_kind(), {0, 0, 0}}, {"a", standard_kind(), {1, 0, 0}}});
  ASSERT_FALSE(world.ok());
  EXPECT_NE(world.error().find("used twice"), std::string::npos) << world.error();
  EXPECT_FALSE(MujocoWorld::make({}).ok());
}

}  // namespace
}  // namespace symb::sim::mujoco
