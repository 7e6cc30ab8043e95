// A scenario's 2D world as an Aseba Playground world file (`.playground`, XML), so the maze and
// the robots' starts can be reproduced in Playground, whose simulated Thymio IIs speak the real
// robot's protocol on TCP (a `symb board --robot aseba:tcp:...` then drives one of them).
//
// Playground reads centimetres and radians as the scenario does, with the arena's sides as its
// world's walls: an inner wall becomes a `<wall>` rectangle (centre, length along its angle,
// thickness, height; the same rectangles the simulators build, IrModel::walls_of), and robot i a
// `<robot type="thymio2">` at its start listening on port first_port + i. Floor zones have no
// counterpart (Playground's floor is an image) and are left out.
#pragma once

#include <cstdint>
#include <string>

#include "symb/kernel/result.hpp"
#include "symb/sim/scenario.hpp"

namespace symb::sim {

// Aseba's port for the first robot.
inline constexpr std::uint16_t kPlaygroundFirstPort = 33333;

// The world file's text. An error for a 3D world, or when the robots' ports would pass 65535.
kernel::Result<std::string> playground_world(const Scenario& scenario, std::uint16_t first_port = kPlaygroundFirstPort);

}  // namespace symb::sim
