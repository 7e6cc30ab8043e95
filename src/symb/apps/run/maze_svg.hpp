// Maze picture: the arena seen from above, its walls drawn to scale, and each robot's path as a
// polyline in its own colour, with a ring where it started, a dot where it ended and a red cross
// wherever it touched something. Plain SVG 1.1: any browser or rsvg-convert shows it. A crowd's
// trails.svg is the same picture of a sample of robots, with every robot's end as a grey dot.
#pragma once

#include <ostream>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "symb/sim/world_spec.hpp"

namespace symb::apps::run {

struct PathPoint {
  double x = 0;  // cm
  double y = 0;
};

struct RobotPath {
  std::string name;
  std::vector<PathPoint> points;    // in time order
  std::vector<PathPoint> contacts;  // where a contact began
};

// `backdrop`: points drawn as small grey dots under the paths (a crowd's end positions).
void write_maze_svg(std::ostream& out, const sim::WorldSpec& world, std::span<const RobotPath> robots,
                    std::string_view caption, std::span<const PathPoint> backdrop = {});

}  // namespace symb::apps::run
