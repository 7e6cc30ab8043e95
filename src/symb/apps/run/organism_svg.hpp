// Organism pictures: what a 3D run of docking modules looked like, for a person to look at
// afterwards (organism_recorder.hpp gathers the data):
//   a path view   every module's path seen from above (x-y) or from the side (x-z), each module
//                 in its own colour (svg_colour(i)), a ring where it started, the outlines of its
//                 two halves at its end pose (the back half turned by the hinge), and a thick
//                 dark line between the centres of each docked pair;
//   topology lanes one lane per module along the time axis, coloured by the component (the
//                 docked group) it belonged to: a colour per group, named by its first module,
//                 light grey while alone;
//   docking lanes  the docking log on the same lanes: a latch as a green dot on both modules'
//                 lanes joined by a line, an unlatch as an orange square likewise, a refusal as a
//                 red cross on the asking module's lane.
// Plain SVG 1.1 through svg.hpp.
#pragma once

#include <array>
#include <cstddef>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "symb/sim/mujoco/mujoco_world.hpp"

namespace symb::apps::run {

struct ModulePath {
  std::string name;
  std::vector<sim::mujoco::Vec3> points;     // m, world frame, time order
  sim::mujoco::Vec3 box_size{};              // the module's box, drawn at the end pose
  sim::mujoco::Vec3 hinge_axis = {0, 1, 0};  // module frame, through the box's centre
  sim::mujoco::Pose3 end;                    // of the front half (the module frame)
  double end_hinge_angle = 0;                // rad: the back half turned about the hinge axis
};

// Two modules docked to each other (indices into the paths).
struct DockedPair {
  std::size_t a = 0, a_connector = 0;
  std::size_t b = 0, b_connector = 0;
  friend bool operator==(const DockedPair&, const DockedPair&) = default;
  friend auto operator<=>(const DockedPair&, const DockedPair&) = default;
};

enum class PathView { kTop, kSide };  // x-y seen from above; x-z seen from -y

void write_path_view_svg(std::ostream& out, PathView view, const std::vector<ModulePath>& modules,
                         const std::vector<DockedPair>& docked_at_end, std::string_view caption);

// The topology from `time` on: component[m] is the index of the first module of m's component.
struct TopologySpan {
  double time = 0;  // s
  std::vector<std::size_t> component;
};

void write_topology_svg(std::ostream& out, const std::vector<std::string>& modules,
                        const std::vector<TopologySpan>& spans, double end_time, std::string_view caption);

void write_docking_svg(std::ostream& out, const std::vector<std::string>& modules,
                       const std::vector<sim::mujoco::DockEvent>& events, double end_time, std::string_view caption);

}  // namespace symb::apps::run
