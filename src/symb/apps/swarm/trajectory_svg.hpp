// Trajectory picture: the arena seen from above with every robot's path drawn as a polyline in
// its own colour, a ring where it started and a dot where it ended. Plain SVG 1.1, no scripts or
// external styles, so any browser or rsvg-convert shows it.
#pragma once

#include <ostream>
#include <span>
#include <string_view>

#include "symb/apps/swarm/trajectory_log.hpp"

namespace symb::apps::swarm {

// `arena` is the side of the square arena in metres; `caption` goes under the picture.
void write_trajectory_svg(std::ostream& out, double arena, std::span<const TrajectoryLog> robots,
                          std::string_view caption);

}  // namespace symb::apps::swarm
