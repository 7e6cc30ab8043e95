// Marked floor zones and the simulated pose and ground sensors: zones parse with located errors,
// the ground model sees a zone exactly where it is, and a robot whose hooks name `pose` or
// `ground` gets those device tasks, fed every control period; one that does not, does not.
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/sim/ground_model.hpp"
#include "symb/sim/scenario.hpp"
#include "symb/sim/scenario_session.hpp"

namespace symb::sim {
namespace {

using namespace std::chrono_literals;

const std::string kZonesHead =
    "name: zones\n"
    "duration: 5s\n"
    "world:\n"
    "  arena: {width: 200, height: 100}\n";

const std::string kZonesRobot =
    "robots:\n"
    "  - name: r\n"
    "    start: {x: 30, y: 50, heading: 0}\n"
    "    tasks:\n"
    "      - {name: drive, type: mdl2e, params: {program: p.mdl2e}}\n"
    "    hooks:\n"
    "      - drive -> wheels\n";

std::string with_zones(const std::string& zones) { return kZonesHead + "  zones:\n" + zones + kZonesRobot; }

void expect_zones_error(const std::string& yaml, const std::string& where, const std::string& what) {
  auto sc = parse_scenario(yaml, "t.yaml");
  ASSERT_FALSE(sc.ok()) << "accepted:\n" << yaml;
  EXPECT_EQ(sc.error().rfind("t.yaml:" + where + ": ", 0), 0u) << sc.error();
  EXPECT_NE(sc.error().find(what), std::string::npos) << sc.error();
}

TEST(FloorZones, RectanglesAndDiscsParse) {
  auto sc = parse_scenario(with_zones("    - {rect: [150, 20, 190, 80], ground: 0.1, name: target}\n"
                                      "    - {circle: [100, 50, 10], ground: 0.5}\n"),
                           "t.yaml");
  ASSERT_TRUE(sc.ok()) << sc.error();
  ASSERT_EQ(sc->world.zones.size(), 2u);
  const ZoneSpec& a = sc->world.zones[0];
  EXPECT_EQ(a.shape, ZoneSpec::Shape::kRect);
  EXPECT_EQ(a.name, "target");
  EXPECT_DOUBLE_EQ(a.x1, 150);
  EXPECT_DOUBLE_EQ(a.y2, 80);
  EXPECT_DOUBLE_EQ(a.ground, 0.1);
  EXPECT_EQ(a.where.line, 6);
  const ZoneSpec& b = sc->world.zones[1];
  EXPECT_EQ(b.shape, ZoneSpec::Shape::kCircle);
  EXPECT_DOUBLE_EQ(b.radius, 10);
}

TEST(FloorZones, MistakesAreReportedWhereTheyAre) {
  expect_zones_error(with_zones("    - {rect: [150, 20, 120, 80], ground: 0.1}\n"), "6:14", "x1 < x2");
  expect_zones_error(with_zones("    - {rect: [150, 20, 190], ground: 0.1}\n"), "6:14", "[x1, y1, x2, y2]");
  expect_zones_error(with_zones("    - {rect: [150, 20, 250, 80], ground: 0.1}\n"), "6:24", "rect x2");
  expect_zones_error(with_zones("    - {circle: [100, 50, 10], ground: 1.5}\n"), "6:39", "ground");
  expect_zones_error(with_zones("    - {circle: [100, 50, 10]}\n"), "6:7", "ground");
  expect_zones_error(with_zones("    - {circle: [100, 50, 10], rect: [1, 1, 2, 2], ground: 0}\n"), "6:7",
                     "exactly one");
  expect_zones_error(with_zones("    - {circel: [100, 50, 10], ground: 0}\n"), "6:8", "did you mean 'circle'");
  expect_zones_error(with_zones("    - [1, 2, 3, 4]\n"), "6:7", "a zone is");
}

TEST(FloorZones, TheGroundModelSeesAZoneUnderTheSensorsOnly) {
  WorldSpec w;
  w.width = 200;
  w.height = 100;
  ZoneSpec z;
  z.x1 = 100;
  z.x2 = 120;
  z.y1 = 0;
  z.y2 = 100;
  z.ground = 0.2f;
  w.zones.push_back(z);
  EXPECT_FLOAT_EQ(floor_reflectance(w, 99.9, 50), 1.0f);
  EXPECT_FLOAT_EQ(floor_reflectance(w, 110, 50), 0.2f);
  // The sensors are 7.2 cm ahead of the centre: a robot at x = 95 facing +x sees the zone, one
  // facing -x does not.
  EXPECT_EQ(ground_readings(w, {95, 50, 0}), (GroundReadings{0.2f, 0.2f}));
  EXPECT_EQ(ground_readings(w, {95, 50, std::numbers::pi}), (GroundReadings{1.0f, 1.0f}));
  // Facing +y with the zone's edge between the two sensors (left is at -x, right at +x).
  EXPECT_EQ(ground_readings(w, {100, 50, std::numbers::pi / 2}), (GroundReadings{1.0f, 0.2f}));
  // Overlapping zones: the last one listed is on top.
  ZoneSpec disc;
  disc.shape = ZoneSpec::Shape::kCircle;
  disc.cx = 110;
  disc.cy = 50;
  disc.radius = 5;
  disc.ground = 0.7;
  w.zones.push_back(disc);
  EXPECT_FLOAT_EQ(floor_reflectance(w, 110, 50), 0.7f);
  EXPECT_FLOAT_EQ(floor_reflectance(w, 110, 60), 0.2f);
}

// Collects what a device task sends.
class Collector : public os::Task {
 public:
  std::vector<std::vector<float>> got;

 protected:
  void on_message(const os::Message& m) override { got.emplace_back(m.numbers().begin(), m.numbers().end()); }
};

TEST(FloorZones, PoseAndGroundDeviceTasksAreMadeWhenHookedAndReportEveryPeriod) {
  const std::string yaml = kZonesHead +
                           "  zones:\n"
                           "    - {rect: [60, 0, 80, 100], ground: 0.1, name: stripe}\n"
                           "robots:\n"
                           "  - name: r\n"
                           "    start: {x: 30, y: 50, heading: 0}\n"
                           "    tasks:\n"
                           "      - {name: drive, type: mdl2e, params: {program: p.mdl2e}}\n"
                           "      - {name: goal, type: move_to_goal}\n"
                           "    hooks:\n"
                           "      - drive -> wheels\n"
                           "      - ir -> drive\n"
                           "      - pose -> goal\n"     // a pose into a task that reads one
                           "      - ground -> drive\n"  // ignored by the controller (wrong length)
                           "  - name: plain\n"
                           "    start: {x: 30, y: 20, heading: 0}\n"
                           "    tasks:\n"
                           "      - {name: drive, type: mdl2e, params: {program: p.mdl2e}}\n"
                           "    hooks:\n"
                           "      - drive -> wheels\n";
  auto sc = parse_scenario(yaml, "t.yaml");
  ASSERT_TRUE(sc.ok()) << sc.error();
  kernel::VirtualTimeExecutor executor;
  SessionOptions so;
  // Forward at 300 units (10 cm/s): over the stripe from about x = 53 (sensors 7.2 cm ahead).
  so.read_program = [](std::string_view) -> kernel::Result<std::string> {
    return std::string("sensor ir[7]\nplan p { atom forward(300) }\n");
  };
  auto session = ScenarioSession::create(*sc, executor, so);
  ASSERT_TRUE(session.ok()) << session.error();
  os::Node& node = (*session)->robot(0).node();
  ASSERT_TRUE(node.find("pose"));
  ASSERT_TRUE(node.find("ground"));
  EXPECT_FALSE((*session)->robot(1).node().find("pose")) << "not hooked: not made";
  EXPECT_FALSE((*session)->robot(1).node().find("ground"));

  auto* pose = new Collector;
  auto* ground = new Collector;
  auto pose_id = node.create("pose_log", std::unique_ptr<os::Task>(pose));
  auto ground_id = node.create("ground_log", std::unique_ptr<os::Task>(ground));
  ASSERT_TRUE(pose_id && ground_id);
  ASSERT_TRUE(node.hook(*node.find("pose"), *pose_id));
  ASSERT_TRUE(node.hook(*node.find("ground"), *ground_id));
  (*session)->start();
  executor.run_for(4s);
  (*session)->stop();

  ASSERT_GE(pose->got.size(), 130u);  // every 30 ms
  ASSERT_EQ(pose->got.size(), ground->got.size());
  const RobotState end = (*session)->world().state(0);
  ASSERT_EQ(pose->got.back().size(), 3u);
  EXPECT_NEAR(pose->got.back()[0], end.pose.x, 1e-3);
  EXPECT_NEAR(pose->got.back()[1], end.pose.y, 1e-3);
  EXPECT_NEAR(pose->got.back()[2], end.pose.theta, 1e-5);
  EXPECT_GT(end.pose.x, 60);
  // On the plain floor first, then over the stripe: both sensors read its value.
  ASSERT_EQ(ground->got.front().size(), 2u);
  EXPECT_EQ(ground->got.front(), (std::vector<float>{1.0f, 1.0f}));
  bool saw_stripe = false;
  for (std::size_t i = 0; i < ground->got.size(); ++i) {
    const bool over = pose->got[i][0] + kGroundSensorX > 60.5 && pose->got[i][0] + kGroundSensorX < 79.5;
    if (over) {
      saw_stripe = true;
      EXPECT_EQ(ground->got[i], (std::vector<float>{0.1f, 0.1f})) << "x " << pose->got[i][0];
    }
  }
  EXPECT_TRUE(saw_stripe);
}

TEST(FloorZones, ADeviceTaskNameIsReserved) {
  expect_zones_error(kZonesHead +
                         "robots:\n  - name: r\n    start: {x: 30, y: 50}\n    tasks:\n"
                         "      - {name: pose, type: mdl2e, params: {program: p.mdl2e}}\n",
                     "9:9", "taken");
}

}  // namespace
}  // namespace symb::sim
