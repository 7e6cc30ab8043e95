// MJCF files: what MuJoCo makes of a model file written to disk (a run's world.xml), counted, so a
// test or a tool can check that a saved model compiles again into the model it was written from
// without including MuJoCo (which the sim library keeps private).
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>

#include "symb/kernel/result.hpp"

namespace symb::sim::mujoco {

// A compiled model's sizes (MuJoCo's nbody, njnt, ngeom, nu, neq, nv): the world body counts.
struct ModelCounts {
  std::size_t bodies = 0;
  std::size_t joints = 0;
  std::size_t geoms = 0;
  std::size_t actuators = 0;
  std::size_t equalities = 0;
  std::size_t degrees_of_freedom = 0;

  friend bool operator==(const ModelCounts&, const ModelCounts&) = default;
};

// Compiles the MJCF file at `path` with MuJoCo's own file loader (mj_loadXML, as its `simulate`
// viewer opens it); or the compiler's message, naming the file.
kernel::Result<ModelCounts> load_mjcf_file(const std::filesystem::path& path);
// The counts of MJCF text compiled from memory (load_mjcf); or the compiler's message.
kernel::Result<ModelCounts> mjcf_counts(const std::string& text);

}  // namespace symb::sim::mujoco
