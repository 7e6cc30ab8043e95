// The robots of a 2D session share one read-only registry of the device-free task types (control,
// evo) and each keeps its own registry for its device task types, whose factories hold its own
// devices (robot_system.hpp, RobotSystemOptions::shared_types).
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/sim/scenario.hpp"
#include "symb/sim/scenario_session.hpp"

namespace symb::sim {
namespace {

using namespace std::chrono_literals;

Scenario three_thymios() {
  const std::string text = std::string(
                               "name: shared_types\nseed: 3\nduration: 2s\ncontrol_period: 30ms\n"
                               "world:\n  arena: {width: 200, height: 200}\n"
                               "robots:\n  - name: t\n    count: 3\n    start: random\n    tasks:\n"
                               "      - name: controller\n        type: mdl2e\n        params: {program: ") +
                           SYMB_SCENARIO_DIR +
                           "/mdl2e/obstacle_avoidance.mdl2e}\n    hooks:\n      - ir -> controller -> wheels\n";
  auto s = parse_scenario(text, "shared_types.yaml");
  EXPECT_TRUE(s) << s.error();
  return s ? std::move(s).value() : Scenario{};
}

TEST(SharedTaskTypes, RobotsShareTheDeviceFreeTypesAndKeepTheirOwnDeviceTypes) {
  kernel::VirtualTimeExecutor executor;
  auto session = ScenarioSession::create(three_thymios(), executor);
  ASSERT_TRUE(session) << session.error();
  ScenarioSession& s = *session.value();
  ASSERT_EQ(s.robot_count(), 3u);
  const os::TaskTypeRegistry& a = s.robot(0).types();
  const os::TaskTypeRegistry& b = s.robot(1).types();
  ASSERT_NE(a.shared(), nullptr);
  EXPECT_EQ(a.shared(), b.shared());
  EXPECT_NE(&a, &b);  // each node looks types up through its own registry
  // One copy of the controller types...
  ASSERT_NE(a.find("mdl2e"), nullptr);
  EXPECT_EQ(a.find("mdl2e"), b.find("mdl2e"));
  EXPECT_EQ(a.find("one_plus_one"), b.find("one_plus_one"));
  // ... and a device type per robot, not in the shared registry.
  ASSERT_NE(a.find("sensor"), nullptr);
  ASSERT_NE(b.find("sensor"), nullptr);
  EXPECT_NE(a.find("sensor"), b.find("sensor"));
  EXPECT_EQ(a.shared()->find("sensor"), nullptr);
  bool lists_sensor = false, lists_mdl2e = false;  // the shell's `types` lists both levels
  for (const os::TaskType* t : a.list()) {
    lists_sensor = lists_sensor || t->name == "sensor";
    lists_mdl2e = lists_mdl2e || t->name == "mdl2e";
  }
  EXPECT_TRUE(lists_sensor && lists_mdl2e);

  // Each robot's device tasks read their own devices: a robot whose sensor task read another's
  // IR sensor would get no readings, its controller would never start, and it would not move.
  s.start();
  executor.run_for(2s);
  for (std::size_t i = 0; i < 3; ++i) EXPECT_GT(s.world().state(i).distance, 1.0) << "robot " << i;
  EXPECT_NE(s.world().state(0).pose.x, s.world().state(1).pose.x);
}

}  // namespace
}  // namespace symb::sim
