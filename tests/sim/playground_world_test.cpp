// The Aseba Playground world generator (sim/playground_world) and the Thymio backend's devices
// seen from the simulation: a scenario's maze becomes Playground walls at the rectangles the
// simulators build, its robots Thymios at their starts on consecutive ports; a 3D world and ports
// past 65535 are refused; and a real Thymio's `ir` and `wheels` have exactly the simulated ones'
// channels and units, so a controller cannot tell them apart.
#include "symb/sim/playground_world.hpp"

#include <gtest/gtest.h>

#include "symb/io/loopback_stream.hpp"
#include "symb/robot/thymio_aseba.hpp"
#include "symb/sim/sim_drivers.hpp"

#include "support/shipped_scenario.hpp"

namespace symb::sim {
namespace {

TEST(PlaygroundWorld, MazeWallsAndRobotStartsInCentimetresAndRadians) {
  Scenario sc = test::load_shipped("maze.yaml");
  auto text = playground_world(sc, 40000);
  ASSERT_TRUE(text) << text.error();
  const std::string& x = *text;
  EXPECT_NE(x.find("<world w=\"200\" h=\"150\" color=\"wall\"/>"), std::string::npos) << x;
  // [50, 0, 50, 100], 2 cm thick: centre (50, 50), 100 + 2 long (capped ends), pointing up.
  EXPECT_NE(x.find("<wall x=\"50\" y=\"50\" l1=\"102\" l2=\"2\" h=\"10\" angle=\"1.5707963267948966\""),
            std::string::npos)
      << x;
  EXPECT_NE(x.find("<wall x=\"100\" y=\"100\" l1=\"102\" l2=\"2\" h=\"10\" angle=\"-1.5707963267948966\""),
            std::string::npos)
      << x;
  EXPECT_NE(x.find("<robot type=\"thymio2\" x=\"25\" y=\"25\" angle=\"1.5707963267948966\" port=\"40000\" "
                   "name=\"thymio\"/>"),
            std::string::npos)
      << x;
  std::size_t walls = 0;
  for (std::size_t at = x.find("<wall "); at != std::string::npos; at = x.find("<wall ", at + 1)) ++walls;
  EXPECT_EQ(walls, sc.world.walls.size());
}

TEST(PlaygroundWorld, RobotsGetConsecutivePortsAndImpossibleWorldsAreRefused) {
  Scenario sc = test::load_shipped("swarm.yaml");
  ASSERT_GE(sc.robots.size(), 2u);
  auto text = playground_world(sc);
  ASSERT_TRUE(text) << text.error();
  EXPECT_NE(text->find("port=\"33333\""), std::string::npos);
  EXPECT_NE(text->find("port=\"" + std::to_string(33333 + sc.robots.size() - 1) + "\""), std::string::npos);
  auto over = playground_world(sc, static_cast<std::uint16_t>(65536 - sc.robots.size() + 1));
  ASSERT_FALSE(over);
  EXPECT_NE(over.error().find("do not fit"), std::string::npos) << over.error();
  Scenario organism = test::load_shipped("caterpillar.yaml");
  auto three_d = playground_world(organism);
  ASSERT_FALSE(three_d);
  EXPECT_NE(three_d.error().find("no Aseba Playground counterpart"), std::string::npos) << three_d.error();
}

TEST(PlaygroundWorld, ThymioOverAsebaHasTheSimulatedDevicesChannels) {
  auto ends = io::make_loopback_pair("aseba");
  auto thymio = robot::thymio::AsebaThymio::create(std::shared_ptr<io::IOStream>(std::move(ends.first)));
  auto same = [](const std::vector<robot::ChannelSpec>& a, const std::vector<robot::ChannelSpec>& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i)
      if (a[i].name != b[i].name || a[i].units != b[i].units || a[i].min != b[i].min || a[i].max != b[i].max)
        return false;
    return true;
  };
  EXPECT_TRUE(same(thymio->ir()->channels(), SimIrSensor::channel_specs()));
  EXPECT_TRUE(same(thymio->wheels()->channels(), SimWheels::channel_specs()));
  EXPECT_TRUE(same(thymio->ground()->channels(), SimGroundSensor::channel_specs()));
  // Playground's Thymio turns 500 units into the simulation's top speed.
  EXPECT_DOUBLE_EQ(robot::thymio::kPlaygroundCmPerSecondPerUnit, kCmPerSecondPerWheelUnit);
}

}  // namespace
}  // namespace symb::sim
