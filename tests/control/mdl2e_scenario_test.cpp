// The scenario programs in scenarios/mdl2e/ parsed and stepped at a 10 ms control period against
// synthetic IR sequences, with the expected primitive at checkpoints and events at transitions.
#include <array>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>

#include <gtest/gtest.h>

#include "mdl2e_test_support.hpp"

namespace symb::control::mdl2e {
namespace {

std::string read_scenario(const std::string& name) {
  std::ifstream f(std::string(SYMB_SCENARIO_DIR) + "/" + name);
  std::stringstream s;
  s << f.rdbuf();
  EXPECT_FALSE(s.str().empty()) << name;
  return s.str();
}

using Sensors = std::function<void(long long t, std::array<double, 7>& ir, std::uint64_t& ext)>;

// Steps every 10 ms up to `end_ms` and returns the atom and events at every step.
std::map<long long, std::pair<std::string, std::string>> run(const Program& p, long long end_ms, const Sensors& s) {
  Interpreter in(p);
  std::map<long long, std::pair<std::string, std::string>> trace;
  for (long long t = 0; t <= end_ms; t += 10) {
    std::array<double, 7> ir{};
    std::uint64_t ext = 0;
    s(t, ir, ext);
    auto o = in.step(testing::ms(t), InterruptInputs{ir, ext});
    trace[t] = {testing::atom(o), testing::events(o)};
  }
  return trace;
}

TEST(Mdl2eScenario, ObstacleAvoidance) {
  const Program p = testing::must_compile(read_scenario("obstacle_avoidance.mdl2e"));
  ASSERT_EQ(p.sensor_count, 7);
  auto trace = run(p, 6000, [](long long t, std::array<double, 7>& ir, std::uint64_t& ext) {
    if (t >= 300 && t < 600) ir[0] = 3000;    // obstacle on the left
    if (t >= 900 && t < 1200) ir[2] = 2500;   // in front, briefly
    if (t >= 1500 && t < 4000) ir[2] = 2500;  // in front, longer than one 2 s turn
    if (t >= 5000) ext = 1;                   // bumped
  });
  const std::map<long long, std::string> expect = {
      {0, "forward(100)"},    {290, "forward(100)"},  {300, "turn(-80)"},     {590, "turn(-80)"},
      {600, "forward(100)"},  {900, "turn(80)"},      {1190, "turn(80)"},     {1200, "forward(100)"},
      {1500, "turn(80)"},     {3490, "turn(80)"},     {3500, "turn(80)"},     {3990, "turn(80)"},
      {4000, "forward(100)"}, {4990, "forward(100)"}, {5000, "backward(50)"}, {5490, "backward(50)"},
      {5500, "ended"},        {6000, "ended"}};
  for (const auto& [t, a] : expect) EXPECT_EQ(trace[t].first, a) << "t=" << t;
  EXPECT_EQ(trace[0].second,
            "started:avoid_obstacles task_action:obstacle_logger/start started:explore started:forward");
  EXPECT_EQ(trace[300].second, "interrupted:forward started:turn");
  EXPECT_EQ(trace[600].second, "interrupted:turn started:turn interrupted:turn started:forward");
  EXPECT_EQ(trace[3500].second,
            "timed_out:turn started:forward interrupted:forward started:turn interrupted:turn started:turn");
  EXPECT_EQ(trace[5000].second, "interrupted:explore started:backward");
  EXPECT_EQ(
      trace[5500].second,
      "timed_out:backward task_action:obstacle_logger/suspend completed:avoid_obstacles plan_ended:avoid_obstacles");
}

TEST(Mdl2eScenario, WallFollowing) {
  const Program p = testing::must_compile(read_scenario("wall_following.mdl2e"));
  auto trace = run(p, 60'010, [](long long t, std::array<double, 7>& ir, std::uint64_t&) {
    ir[4] = 2000;                             // wall on the right at a good distance
    if (t >= 500 && t < 800) ir[4] = 3500;    // too close
    if (t >= 1000 && t < 2500) ir[4] = 500;   // too far, for longer than one 1 s veer
    if (t >= 3000 && t < 3300) ir[2] = 3000;  // wall ahead
  });
  const std::map<long long, std::string> expect = {
      {0, "forward(100)"},      {490, "forward(100)"},    {500, "wheels(60,100)"},  {790, "wheels(60,100)"},
      {800, "forward(100)"},    {1000, "wheels(100,60)"}, {1990, "wheels(100,60)"}, {2000, "wheels(100,60)"},
      {2490, "wheels(100,60)"}, {2500, "forward(100)"},   {3000, "turn(60)"},       {3290, "turn(60)"},
      {3300, "forward(100)"},   {59990, "forward(100)"},  {60000, "ended"}};
  for (const auto& [t, a] : expect) EXPECT_EQ(trace[t].first, a) << "t=" << t;
  EXPECT_EQ(trace[500].second, "interrupted:forward started:turn interrupted:turn started:veer_left started:wheels");
  EXPECT_NE(trace[2000].second.find("timed_out:veer_right"), std::string::npos) << trace[2000].second;
  EXPECT_EQ(trace[60000].second, "timed_out:follow_right_wall plan_ended:follow_right_wall");
}

}  // namespace
}  // namespace symb::control::mdl2e
