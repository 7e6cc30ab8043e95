// Module kind files: a ModuleKind (module_kind.hpp) written as YAML, so a kind is data a scenario
// can name rather than code. docs/modules.md gives the format, every key's unit and range, and a
// complete example; scenarios/modules/ holds the shipped kinds (cube.yaml is standard_kind(),
// long.yaml is long_kind(), field for field).
//
// Every key is required (a file describes its kind completely; nothing comes from defaults), an
// unknown key is refused with the closest known one, and every number is checked for finiteness
// and range where it is read. Then the rules between values: the wheels fit the body, the hinge
// range runs low to high, each connector and IR sensor lies on the face it names, names and IR
// faces are unique. Every error is "file:LINE:COLUMN: what" at the value that broke the rule.
// The text is bounded before it is read (kMaxModuleKindBytes, kMaxModuleKindNesting) and the
// lists by kMaxConnectors and one IR sensor per face, so no input crashes, hangs or allocates
// without bound; nothing is thrown.
//
//   auto kind = load_module_kind("scenarios/modules/cube.yaml");
//   if (!kind) return report(kind.error());   // "scenarios/modules/cube.yaml:12:14: body mass ..."
//   auto world = MujocoWorld::make({{"a", *kind, {0, 0, 0}}});
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

#include "symb/kernel/result.hpp"
#include "symb/sim/mujoco/module_kind.hpp"

namespace symb::sim::mujoco {

inline constexpr std::size_t kMaxModuleKindBytes = 64 * 1024;
inline constexpr int kMaxModuleKindNesting = 8;  // mappings and sequences inside each other
inline constexpr std::size_t kMaxConnectors = 16;

// Text -> ModuleKind; `file_name` is the file part of every error message.
kernel::Result<ModuleKind> parse_module_kind(std::string_view yaml_text, std::string_view file_name);

// Reads the file at `path` (at most kMaxModuleKindBytes) and parses it.
kernel::Result<ModuleKind> load_module_kind(const std::string& path);

}  // namespace symb::sim::mujoco
