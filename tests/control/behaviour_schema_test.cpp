// Motor schemas and their summing task in a node under virtual time: each schema's vector against
// values computed by hand (Arkin's avoid magnitude G (S - d) / (S - R), move-to-goal, stay-on-path,
// noise), the summing task's rate, freshness rule and wheel speeds, schemas at their own rates,
// probes, and the task types' parameter errors (a malformed waypoint list: which waypoint, which
// column).
#include <cmath>
#include <functional>
#include <memory>
#include <numbers>
#include <optional>
#include <vector>

#include <gtest/gtest.h>

#include "symb/control/control_task_types.hpp"
#include "symb/control/schemas/schema_tasks.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/robot/thymio_ir.hpp"

#include "support/virtual_time.hpp"

namespace symb::control {
namespace {

using namespace std::chrono_literals;
using kernel::Time;
using robot::thymio::ir_distance;
using robot::thymio::ir_reading;
using Values = std::vector<float>;

using test_support::ms;

class SchemaSensor : public os::Task {
 public:
  explicit SchemaSensor(std::function<std::optional<Values>(Time)> script) : script_(std::move(script)) {}

 protected:
  void on_tick() override {
    if (auto v = script_(now())) send(0, *v);
  }

 private:
  std::function<std::optional<Values>(Time)> script_;
};

struct Sample {
  Time time;
  Values v;
};
class SchemaRecorder : public os::Task {
 public:
  std::vector<Sample> got;

 protected:
  void on_message(const os::Message& m) override {
    got.push_back({m.time, Values(m.numbers().begin(), m.numbers().end())});
  }
};

struct SchemaRig {
  kernel::VirtualTimeExecutor ex;
  os::TaskTypeRegistry types;
  os::Node node;
  SchemaRig() : node(ex, {.name = "bot", .seed = 3, .types = &types}) {
    EXPECT_TRUE(register_control_task_types(types, {}).ok());
  }
  os::TaskId sensor(std::string name, std::function<std::optional<Values>(Time)> script,
                    kernel::Duration period = 30ms) {
    return *node.create(std::move(name), std::make_unique<SchemaSensor>(std::move(script)),
                        {.priority = 5, .period = period});
  }
  std::pair<os::TaskId, SchemaRecorder*> recorder(std::string name) {
    auto r = std::make_unique<SchemaRecorder>();
    SchemaRecorder* p = r.get();
    return {*node.create(std::move(name), std::move(r), {.queue_capacity = 256}), p};
  }
  os::TaskId make(std::string_view type, std::string name, std::vector<os::ParamAssignment> params,
                  std::optional<os::TaskOptions> options = std::nullopt) {
    auto id = node.create(type, std::move(name), params, options);
    EXPECT_TRUE(id.ok()) << (id ? "" : id.error());
    return id ? *id : os::TaskId{};
  }
  std::string error(std::string_view type, std::vector<os::ParamAssignment> params) {
    auto id = node.create(type, "bad", params);
    if (id) {
      (void)node.remove(*id);
      return "";
    }
    return id.error();
  }
};

Values ir_with(std::size_t sensor, double distance_cm) {
  Values v(7, 0.0f);
  v[sensor] = static_cast<float>(ir_reading(distance_cm));
  return v;
}

// --- the IR curve ----------------------------------------------------------------------------------

TEST(ThymioIr, DistanceInvertsTheResponseCurve) {
  for (double d : {0.5, 1.0, 3.0, 7.0, 10.0, 13.5}) EXPECT_NEAR(ir_distance(ir_reading(d)), d, 1e-6) << d;
  EXPECT_EQ(ir_distance(0), robot::thymio::kIrRange);
  EXPECT_EQ(ir_distance(4505), 0.0);
  EXPECT_EQ(ir_distance(std::nan("")), robot::thymio::kIrRange);
  EXPECT_NEAR(ir_reading(10), 4505.0 * (73 - 0.0009) / (100 - 0.6 + 73), 1e-9);
}

// --- avoid_obstacle --------------------------------------------------------------------------------

TEST(AvoidObstacleSchema, MagnitudeIsGTimesSMinusDOverSMinusRAwayFromTheObstacle) {
  AvoidObstacleOptions o;
  o.gain = 2;
  o.sphere = 12;
  o.safety = 1;
  o.near_gain = 5;
  // Centre sensor, obstacle 5 cm ahead: 2 (12 - 5) / (12 - 1) straight back.
  Values ir = ir_with(2, 5);
  Vec2 v = AvoidObstacleSchema::vector_for(ir, o);
  EXPECT_NEAR(v.x, -2.0 * 7 / 11, 1e-4);
  EXPECT_NEAR(v.y, 0, 1e-9);
  // Beyond S: nothing.
  v = AvoidObstacleSchema::vector_for(ir_with(2, 13), o);
  EXPECT_EQ(v.x, 0);
  EXPECT_EQ(v.y, 0);
  // Within R: G * near_gain.
  v = AvoidObstacleSchema::vector_for(ir_with(2, 0.5), o);
  EXPECT_NEAR(v.x, -10, 1e-9);
  // Far-left sensor (mount (6.2, 4.85), 40 degrees), obstacle 8 cm out: away from the point
  // mount + 8 (cos 40, sin 40), magnitude 2 (12 - 8) / 11.
  v = AvoidObstacleSchema::vector_for(ir_with(0, 8), o);
  const double px = 6.2 + 8 * std::cos(0.69813), py = 4.85 + 8 * std::sin(0.69813);
  const double m = 2.0 * 4 / 11, n = std::hypot(px, py);
  EXPECT_NEAR(v.x, -m * px / n, 1e-4);
  EXPECT_NEAR(v.y, -m * py / n, 1e-4);
}

TEST(AvoidObstacleSchema, SumAddsObstaclesMaxTakesTheStrongestMagnitude) {
  AvoidObstacleOptions o;
  o.gain = 1;
  o.sphere = 12;
  o.safety = 1;
  // Both rear sensors see something at 6 cm: each 6/11, both pushing forward.
  Values ir(7, 0.0f);
  ir[5] = ir[6] = static_cast<float>(ir_reading(6));
  const double m = 6.0 / 11;
  // Each obstacle sits at mount + 6 (-1, 0) = (-8.95, +-2.95): the y parts cancel.
  const double ux = 8.95 / std::hypot(8.95, 2.95);
  o.use_max = false;
  Vec2 v = AvoidObstacleSchema::vector_for(ir, o);
  EXPECT_NEAR(v.x, 2 * m * ux, 1e-4);
  EXPECT_NEAR(v.y, 0, 1e-4);
  o.use_max = true;  // Balch: one obstacle's worth, in the summed direction
  v = AvoidObstacleSchema::vector_for(ir, o);
  EXPECT_NEAR(v.x, m, 1e-4);
  EXPECT_NEAR(v.y, 0, 1e-4);
}

TEST(AvoidObstacleSchema, AsATaskEvaluatesAtEveryReadingAndProbesItsVector) {
  SchemaRig rig;
  const auto ir = rig.sensor("ir", [](Time t) -> std::optional<Values> {
    if (t == ms(60)) return Values{1, 2};  // malformed: ignored
    return t >= ms(90) ? ir_with(2, 5) : Values(7, 0.0f);
  });
  const auto schema = rig.make("avoid_obstacle", "avoid", {{"gain", "2"}});
  const auto recorded = rig.recorder("sum");  // no structured binding: lambdas capture rec (clang)
  const auto rec_id = recorded.first;
  const auto rec = recorded.second;
  ASSERT_TRUE(rig.node.hook(ir, schema));
  ASSERT_TRUE(rig.node.hook(schema, rec_id));
  std::vector<std::pair<std::string, Values>> probes;
  rig.node.set_probe_sink([&](const os::ProbeSample& s) {
    probes.push_back({std::string(s.channel), Values(s.values.begin(), s.values.end())});
  });
  rig.ex.run_until(ms(150));
  ASSERT_EQ(rec->got.size(), 4u);  // 30, 90, 120, 150 (60 was malformed)
  EXPECT_EQ(rec->got[0].v, (Values{0, 0}));
  EXPECT_NEAR(rec->got[1].v[0], -2.0 * 7 / 11, 1e-4);
  ASSERT_EQ(probes.size(), 8u);
  EXPECT_EQ(probes[2].first, "vector");
  EXPECT_NEAR(probes[2].second[0], -2.0 * 7 / 11, 1e-4);
  EXPECT_EQ(probes[3], (std::pair<std::string, Values>{"active", {1.0f}}));
}

// --- move_to_goal ----------------------------------------------------------------------------------

TEST(MoveToGoalSchema, PointsTowardTheNextWaypointThenTheGoalInTheRobotFrame) {
  SchemaRig rig;
  Values pose{0, 0, 0};
  const auto pose_task = rig.sensor("pose", [&](Time) { return pose; });
  const auto schema = rig.make(
      "move_to_goal", "goal",
      {{"gain", "0.8"}, {"goal_x", "100"}, {"goal_y", "0"}, {"via", "0,50; 50,50"}, {"reach", "10"}, {"arrive", "3"}},
      os::TaskOptions{.priority = 2, .period = 100ms});
  const auto recorded = rig.recorder("sum");  // no structured binding: lambdas capture rec (clang)
  const auto rec_id = recorded.first;
  const auto rec = recorded.second;
  ASSERT_TRUE(rig.node.hook(pose_task, schema));
  ASSERT_TRUE(rig.node.hook(schema, rec_id));
  const auto last = [&] { return rec->got.back().v; };
  rig.ex.run_until(ms(100));
  // Facing +x, the first waypoint (0, 50) is straight to the left.
  ASSERT_EQ(rec->got.size(), 1u);
  EXPECT_NEAR(last()[0], 0, 1e-6);
  EXPECT_NEAR(last()[1], 0.8, 1e-6);
  // Facing +y (heading pi/2) at (0, 45): within reach of (0, 50), so next is (50, 50): to the right
  // and ahead: world (50, 5) -> robot (5, -50).
  pose = {0, 45, static_cast<float>(std::numbers::pi / 2)};
  rig.ex.run_until(ms(200));
  const double n = std::hypot(5.0, 50.0);
  EXPECT_NEAR(last()[0], 0.8 * 5 / n, 1e-5);
  EXPECT_NEAR(last()[1], -0.8 * 50 / n, 1e-5);
  // Past both waypoints: the goal.
  pose = {50, 45, 0};
  rig.ex.run_until(ms(300));
  EXPECT_NEAR(last()[0], 0.8 * 50 / std::hypot(50.0, 45.0), 1e-5);
  EXPECT_NEAR(last()[1], -0.8 * 45 / std::hypot(50.0, 45.0), 1e-5);
  // Within `arrive` of the goal: rest.
  pose = {98, 1, 0};
  rig.ex.run_until(ms(400));
  EXPECT_EQ(last(), (Values{0, 0}));
  // Its own rate: one vector per 100 ms tick although the pose comes every 30 ms.
  EXPECT_EQ(rec->got.size(), 4u);
}

// --- stay_on_path ----------------------------------------------------------------------------------

TEST(StayOnPathSchema, PullsTowardTheCentreLineProportionallyInsideAndFullyOutside) {
  SchemaRig rig;
  Values pose{50, 5, 0};
  const auto pose_task = rig.sensor("pose", [&](Time) { return pose; });
  const auto schema =
      rig.make("stay_on_path", "path", {{"gain", "0.6"}, {"path", "0,0;100,0;100,100"}, {"width", "20"}},
               os::TaskOptions{.period = 0ns});
  const auto recorded = rig.recorder("sum");  // no structured binding: lambdas capture rec (clang)
  const auto rec_id = recorded.first;
  const auto rec = recorded.second;
  ASSERT_TRUE(rig.node.hook(pose_task, schema));
  ASSERT_TRUE(rig.node.hook(schema, rec_id));
  rig.ex.run_until(ms(30));
  // 5 cm left of the line, half width 10: 0.6 * 5 / 10 to the right.
  EXPECT_NEAR(rec->got.back().v[0], 0, 1e-6);
  EXPECT_NEAR(rec->got.back().v[1], -0.3, 1e-6);
  pose = {50, 30, 0};  // outside: full gain
  rig.ex.run_until(ms(60));
  EXPECT_NEAR(rec->got.back().v[1], -0.6, 1e-6);
  pose = {50, 0, 0};  // on the line: nothing
  rig.ex.run_until(ms(90));
  EXPECT_EQ(rec->got.back().v, (Values{0, 0}));
  // Progress to the second segment: at (110, 60) the nearest point is (100, 60), 10 cm to the left
  // of the robot facing +y... world (-10, 0) seen with heading pi/2 is robot (0, 10): full gain.
  pose = {110, 60, static_cast<float>(std::numbers::pi / 2)};
  rig.ex.run_until(ms(120));
  EXPECT_NEAR(rec->got.back().v[0], 0, 1e-5);
  EXPECT_NEAR(rec->got.back().v[1], 0.6, 1e-5);
}

// --- noise -----------------------------------------------------------------------------------------

TEST(NoiseSchema, HoldsARandomDirectionOfMagnitudeGForItsPersistence) {
  SchemaRig rig;
  const auto schema =
      rig.make("noise", "noise", {{"gain", "0.5"}, {"persistence", "300ms"}}, os::TaskOptions{.period = 100ms});
  const auto recorded = rig.recorder("sum");  // no structured binding: lambdas capture rec (clang)
  const auto rec_id = recorded.first;
  const auto rec = recorded.second;
  ASSERT_TRUE(rig.node.hook(schema, rec_id));
  rig.ex.run_until(ms(1200));
  ASSERT_EQ(rec->got.size(), 12u);
  for (const auto& s : rec->got) EXPECT_NEAR(std::hypot(s.v[0], s.v[1]), 0.5, 1e-6);
  // Drawn at 100, held through 300; drawn again at 400 ...
  EXPECT_EQ(rec->got[0].v, rec->got[2].v);
  EXPECT_NE(rec->got[2].v, rec->got[3].v);
  EXPECT_EQ(rec->got[3].v, rec->got[5].v);
}

// --- the sum ---------------------------------------------------------------------------------------

TEST(SchemaSum, WheelSpeedsTurnTowardTheVector) {
  SchemaSumOptions o;
  o.speed = 300;
  o.turn_speed = 150;
  auto w = SchemaSum::wheels_for({1, 0}, o);
  EXPECT_EQ(w, (std::pair<float, float>{300, 300}));
  w = SchemaSum::wheels_for({0.5, 0}, o);  // half magnitude: half speed
  EXPECT_EQ(w, (std::pair<float, float>{150, 150}));
  w = SchemaSum::wheels_for({0, 2}, o);  // to the left: on the spot, counter-clockwise
  EXPECT_NEAR(w.first, -150, 1e-3);
  EXPECT_NEAR(w.second, 150, 1e-3);
  w = SchemaSum::wheels_for({1, 1}, o);  // 45 degrees: 300 cos 45 forward, half the turn
  EXPECT_NEAR(w.first, 300 * std::cos(std::numbers::pi / 4) - 75, 1e-3);
  EXPECT_NEAR(w.second, 300 * std::cos(std::numbers::pi / 4) + 75, 1e-3);
  w = SchemaSum::wheels_for({-1, -0.01}, o);  // behind: turn on the spot, clockwise
  EXPECT_NEAR(w.first, 150, 1e-3);
  EXPECT_NEAR(w.second, -150, 1e-3);
  w = SchemaSum::wheels_for({0.01, 0.01}, o);  // below min_magnitude: stop
  EXPECT_EQ(w, (std::pair<float, float>{0, 0}));
}

// Sends a fixed vector at every tick until `until`.
std::function<std::optional<Values>(Time)> vector_until(Values v, Time until) {
  return [v, until](Time t) -> std::optional<Values> {
    if (t > until) return std::nullopt;
    return v;
  };
}

TEST(SchemaSum, SumsTheFreshVectorsAtItsOwnRate) {
  SchemaRig rig;
  const auto a = rig.sensor("a", vector_until({0.5, 0.25}, ms(10000)), 50ms);
  const auto b = rig.sensor("b", vector_until({0.3, -0.25}, ms(200)), 70ms);  // goes silent after 140
  const auto sum = rig.make("schema_sum", "sum", {{"speed", "400"}, {"turn_speed", "100"}, {"max_age", "200ms"}},
                            os::TaskOptions{.priority = 1, .period = 30ms, .queue_capacity = 16});
  const auto recorded = rig.recorder("wheels");  // no structured binding: lambdas capture rec (clang)
  const auto rec_id = recorded.first;
  const auto rec = recorded.second;
  ASSERT_TRUE(rig.node.hook(a, sum));
  ASSERT_TRUE(rig.node.hook(b, sum));
  ASSERT_TRUE(rig.node.hook(sum, rec_id));
  std::vector<Sample> sums;
  rig.node.set_probe_sink([&](const os::ProbeSample& s) {
    if (s.channel == "sum") sums.push_back({s.time, Values(s.values.begin(), s.values.end())});
  });
  rig.ex.run_until(ms(600));
  // Rate: one command per 30 ms tick, whatever the schemas' rates.
  ASSERT_EQ(rec->got.size(), 20u);
  for (std::size_t k = 0; k < rec->got.size(); ++k) EXPECT_EQ(rec->got[k].time, ms(30 * (k + 1)));
  ASSERT_EQ(sums.size(), 20u);
  const auto sum_at = [&](long long t) {
    for (const auto& s : sums)
      if (s.time == ms(t)) return s.v;
    return Values{};
  };
  EXPECT_EQ(sum_at(30), (Values{0, 0}));  // nothing yet: a speaks at 50, b at 70
  EXPECT_EQ(sum_at(60), (Values{0.5f, 0.25f}));
  EXPECT_NEAR(sum_at(150)[0], 0.8, 1e-6);  // both
  EXPECT_NEAR(sum_at(150)[1], 0.0, 1e-6);
  EXPECT_NEAR(rec->got[4].v[0], 400 * 0.8, 1e-3);  // at 150: straight on, magnitude 0.8
  EXPECT_NEAR(rec->got[4].v[1], 400 * 0.8, 1e-3);
  // b's last vector (140) is older than 200 ms from 360 on: a alone again.
  EXPECT_NEAR(sum_at(330)[0], 0.8, 1e-6);
  EXPECT_EQ(sum_at(360), (Values{0.5f, 0.25f}));
  const double angle = std::atan2(0.25, 0.5), mag = std::hypot(0.5, 0.25);
  const Values w = rec->got[11].v;  // 360
  EXPECT_NEAR(w[0], 400 * mag * std::cos(angle) - 100 * angle / (std::numbers::pi / 2), 1e-3);
  EXPECT_NEAR(w[1], 400 * mag * std::cos(angle) + 100 * angle / (std::numbers::pi / 2), 1e-3);
}

TEST(SchemaSum, SchemasAtTheirOwnRatesDriveOneRobot) {
  // avoid_obstacle at every IR reading (30 ms), move_to_goal every 100 ms, noise every 250 ms,
  // the sum every 30 ms.
  SchemaRig rig;
  const auto ir = rig.sensor("ir", [](Time) { return Values(7, 0.0f); });
  const auto pose = rig.sensor("pose", [](Time) { return Values{0, 0, 0}; });
  const auto avoid = rig.make("avoid_obstacle", "avoid", {});
  const auto goal = rig.make("move_to_goal", "goal", {{"goal_x", "100"}});
  const auto noise = rig.make("noise", "noise", {{"gain", "0.1"}}, os::TaskOptions{.period = 250ms});
  const auto sum = rig.make("schema_sum", "sum", {});
  const auto recorded = rig.recorder("wheels");  // no structured binding: lambdas capture rec (clang)
  const auto rec_id = recorded.first;
  const auto rec = recorded.second;
  ASSERT_TRUE(rig.node.hook(ir, avoid));
  ASSERT_TRUE(rig.node.hook(pose, goal));
  for (auto s : {avoid, goal, noise}) ASSERT_TRUE(rig.node.hook(s, sum));
  ASSERT_TRUE(rig.node.hook(sum, rec_id));
  rig.ex.run_until(ms(3000));
  EXPECT_EQ(rig.node.info(avoid)->traffic.delivered, 100u);
  EXPECT_EQ(rig.node.info(sum)->traffic.delivered, 100u + 30u + 12u);
  EXPECT_EQ(rec->got.size(), 100u);
  // Goal ahead, noise small: forward, close to straight.
  for (std::size_t k = 4; k < rec->got.size(); ++k) {
    EXPECT_GT(rec->got[k].v[0] + rec->got[k].v[1], 300.0f);
    EXPECT_LT(std::abs(rec->got[k].v[0] - rec->got[k].v[1]), 40.0f);
  }
}

// --- parameters ------------------------------------------------------------------------------------

TEST(SchemaTypes, BadParametersAreRejectedWithTheirLocation) {
  SchemaRig rig;
  const auto has = [](const std::string& error, std::string_view part) {
    return error.find(part) != std::string::npos;
  };
  std::string e = rig.error("move_to_goal", {{"via", "10,20;30,x0"}});
  EXPECT_TRUE(has(e, "via: waypoint 2, column 10: expected y (a number), got 'x'")) << e;
  e = rig.error("stay_on_path", {{"path", "0,0"}});
  EXPECT_TRUE(has(e, "path: needs at least 2 waypoints, got 1")) << e;
  e = rig.error("stay_on_path", {{"path", "0,0;5 5"}});
  EXPECT_TRUE(has(e, "path: waypoint 2, column 7: expected ',' between x and y, got '5'")) << e;
  e = rig.error("avoid_obstacle", {{"combine", "avg"}});
  EXPECT_TRUE(has(e, "combine must be 'max' or 'sum'")) << e;
  e = rig.error("avoid_obstacle", {{"sphere", "5"}, {"safety", "6"}});
  EXPECT_TRUE(has(e, "safety (R) must be less than sphere (S)")) << e;
  e = rig.error("avoid_obstacle", {{"sphere", "20"}});
  EXPECT_TRUE(has(e, "sphere")) << e;
  e = rig.error("schema_sum", {{"max_age", "5"}});  // a duration needs its unit
  EXPECT_TRUE(has(e, "max_age")) << e;
  e = rig.error("noise", {{"gian", "1"}});
  EXPECT_TRUE(has(e, "gain")) << e;  // did you mean
  // Runtime changes: checked by the same rules, the bad one refused, the task unchanged.
  const auto goal = rig.make("move_to_goal", "goal", {{"goal_x", "10"}});
  EXPECT_TRUE(rig.node.set_parameter(goal, "via", "1,1;2,2").ok());
  EXPECT_TRUE(rig.node.set_parameter(goal, "goal_y", "-4.5").ok());
  rig.ex.run_until(ms(10));  // parameters are applied on the task's own context
  EXPECT_EQ(rig.node.parameters(goal)->string("via"), "1,1;2,2");
}

}  // namespace
}  // namespace symb::control
