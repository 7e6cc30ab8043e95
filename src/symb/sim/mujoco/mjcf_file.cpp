#include "symb/sim/mujoco/mjcf_file.hpp"

#include <array>

#include <mujoco/mujoco.h>

#include "symb/sim/mujoco/mjcf_model.hpp"

namespace symb::sim::mujoco {

namespace {

ModelCounts counts_of(const mjModel& m) {
  const auto n = [](int v) { return static_cast<std::size_t>(v); };
  return {n(m.nbody), n(m.njnt), n(m.ngeom), n(m.nu), n(m.neq), n(m.nv)};
}

}  // namespace

kernel::Result<ModelCounts> load_mjcf_file(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return kernel::Error{path.string() + ": no such file"};
  std::array<char, 1000> error{};
  mjModel* model = mj_loadXML(path.c_str(), nullptr, error.data(), static_cast<int>(error.size()));
  if (model == nullptr) return kernel::Error{path.string() + ": MuJoCo could not compile it: " + error.data()};
  const ModelCounts counts = counts_of(*model);
  mj_deleteModel(model);
  return counts;
}

kernel::Result<ModelCounts> mjcf_counts(const std::string& text) {
  auto model = load_mjcf(text);
  if (!model) return kernel::Error{model.error()};
  return counts_of(**model);
}

}  // namespace symb::sim::mujoco
