// Waypoints: a path as text, "x1,y1;x2,y2;...", in the world's centimetres. Motor schemas take a
// path or a chain of intermediate goals as one task parameter, so it must come as text through the
// parameter schema (shell, scenario files) and be read here, once, with errors that say which
// waypoint and which character (1-based column in the whole text) went wrong.
#pragma once

#include <cstddef>
#include <string_view>
#include <vector>

#include "symb/kernel/result.hpp"

namespace symb::control::behaviour {

struct Point {
  double x = 0, y = 0;
};

// Most waypoints one parameter may carry: a path is a few corridors, not a map.
inline constexpr std::size_t kMaxWaypoints = 256;

// Reads "x,y;x,y;...". Spaces around numbers and separators are allowed; an empty text gives no
// points; a trailing ';' is allowed. Numbers are finite decimals within +-1e6.
// Errors: "waypoint N, column C: what".
kernel::Result<std::vector<Point>> parse_waypoints(std::string_view text);

}  // namespace symb::control::behaviour
