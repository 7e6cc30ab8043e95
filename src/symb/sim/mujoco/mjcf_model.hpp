// MJCF model: the MuJoCo XML text for a set of modules on a floor, generated from their kinds
// (module_kind.hpp), and its loading from memory. The text is the whole model: a user can save it
// and open it in MuJoCo's own viewer.
//
// What the text holds, and why:
// - One free body per module ("<name>.base"), its hinged back half ("<name>.tail"), and with
//   wheels its two wheel bodies ("<name>.wheel_l", "<name>.wheel_r"); joints and actuators carry
//   the same names ("<name>.hinge", "<name>.wheel_l", ...; MuJoCo keeps one namespace per type).
// - A fixed pool of spare weld equalities ("spare_weld_<k>"), declared inactive. Docking retargets
//   a free one to the pair's bodies and switches it on; undocking switches it off. The model is
//   never recompiled while running (MuJoCo 2.2.2 reserves constraint rows for inactive welds).
// - Static obstacles ("obstacle_<k>"): boxes standing on the floor, geoms of the world body, so
//   the IR, the laser and the camera have something to see beside modules.
// - Explicit `<size njmax nconmax nstack>`: 2.2.2 allocates its constraint and stack memory up
//   front, and its default stack heuristic overflows on large organisms. The stack is sized from
//   what 2.2.2 was measured to use (mjcf_model.cpp: kStackPerDof2 and kStackPerRow, times
//   kStackSafety), not from the dense solver's worst case, which for 50 modules reserved 234 MB
//   of a peak use of 8 MB.
// - A 2 ms time step (Euler): at 5 ms a welded chain blows up in 2.2.2.
// - `<compiler angle="radian">`: MJCF's default unit for angles (hinge ranges) is degrees.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "symb/kernel/result.hpp"
#include "symb/sim/mujoco/module_kind.hpp"

struct mjModel_;

namespace symb::sim::mujoco {

inline constexpr double kTimestep = 0.002;  // s, the model's only step

// Where a module starts: on the floor, at (x, y) metres, turned by yaw radians about z.
struct StartPose {
  double x = 0;
  double y = 0;
  double yaw = 0;
};

struct ModuleSpec {
  std::string name;  // letters, digits and '_' only; unique in the model
  ModuleKind kind;
  StartPose start;
};

// A static box standing on the floor: its centre at (x, y), turned by yaw radians about z.
struct Obstacle {
  double x = 0;
  double y = 0;
  double yaw = 0;
  Vec3 size = {0.1, 0.1, 0.1};  // full extent along its own x, y, z, m, each in (0, 100]
};

struct ModelOptions {
  std::size_t spare_welds = 8;        // how many docks can be latched at once
  double weld_time_constant = 0.005;  // s, the welds' solref time constant (>= 2 time steps)
  std::vector<Obstacle> obstacles;    // obstacle k is "obstacle_<k>"; at most kMaxObstacles
};

inline constexpr std::size_t kMaxObstacles = 10000;

// The scratch stack (numbers) the model reserves for `dofs` degrees of freedom and `rows`
// constraint rows (njmax): kStackSafety times what MuJoCo 2.2.2 was measured to need.
std::size_t stack_numbers(std::size_t dofs, std::size_t rows);

// The MJCF text, or why the modules cannot make a model (a bad name or kind).
kernel::Result<std::string> mjcf_text(const std::vector<ModuleSpec>& modules, const ModelOptions& options);

// Owns a compiled mjModel and frees it.
struct ModelDeleter {
  void operator()(mjModel_* model) const;
};
using ModelPtr = std::unique_ptr<mjModel_, ModelDeleter>;

// Compiles MJCF text held in memory (through MuJoCo's virtual file system: no file is written);
// on failure the compiler's message.
kernel::Result<ModelPtr> load_mjcf(const std::string& text);

}  // namespace symb::sim::mujoco
