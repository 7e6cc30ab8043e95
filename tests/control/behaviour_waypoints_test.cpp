// The waypoint list parser ("x1,y1;x2,y2;..."): accepted forms, and errors that name the waypoint
// and the column.
#include <string>

#include <gtest/gtest.h>

#include "symb/control/schemas/waypoints.hpp"

namespace symb::control::behaviour {
namespace {

std::string waypoints_error(std::string_view text) {
  auto r = parse_waypoints(text);
  return r ? std::string("accepted") : r.error();
}

TEST(Waypoints, ReadsPointsWithSpacesSignsAndExponents) {
  auto r = parse_waypoints(" 25,125 ; 75.5 , -1e1;+3,.5; ");
  ASSERT_TRUE(r.ok()) << r.error();
  ASSERT_EQ(r->size(), 3u);
  EXPECT_EQ((*r)[0].x, 25);
  EXPECT_EQ((*r)[0].y, 125);
  EXPECT_EQ((*r)[1].x, 75.5);
  EXPECT_EQ((*r)[1].y, -10);
  EXPECT_EQ((*r)[2].x, 3);
  EXPECT_EQ((*r)[2].y, 0.5);
  EXPECT_TRUE(parse_waypoints("")->empty());
  EXPECT_TRUE(parse_waypoints("   ")->empty());
}

TEST(Waypoints, ErrorsNameTheWaypointAndTheColumn) {
  EXPECT_EQ(waypoints_error("1,2;3"), "waypoint 2, column 6: expected ',' and then y, got the end of the text");
  EXPECT_EQ(waypoints_error("1,2;3,"), "waypoint 2, column 7: expected y, got the end of the text");
  EXPECT_EQ(waypoints_error("1,2;;3,4"), "waypoint 2, column 5: expected x (a number), got ';'");
  EXPECT_EQ(waypoints_error("1,2 3,4"), "waypoint 1, column 5: expected ';' after the waypoint, got '3'");
  EXPECT_EQ(waypoints_error("1.2.3,4"), "waypoint 1, column 4: expected x (a number), got '.'");
  EXPECT_EQ(waypoints_error("a,1"), "waypoint 1, column 1: expected x (a number), got 'a'");
  EXPECT_EQ(waypoints_error("1,2e999"), "waypoint 1, column 3: expected y (a number), got '2'");
  EXPECT_EQ(waypoints_error("1,2e7"), "waypoint 1, column 3: y must be within +-1e6 cm");
  EXPECT_EQ(waypoints_error("1,nan"), "waypoint 1, column 3: expected y (a number), got 'n'");
  EXPECT_EQ(waypoints_error(std::string("1,\x01", 3)), "waypoint 1, column 3: expected y (a number), got byte 1");
  std::string many;
  for (int k = 0; k <= static_cast<int>(kMaxWaypoints); ++k) many += "1,1;";
  EXPECT_EQ(waypoints_error(many), "waypoint 257, column 1025: more than 256 waypoints");
}

}  // namespace
}  // namespace symb::control::behaviour
