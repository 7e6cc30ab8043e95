// Control task types: the control layer's entries in a TaskTypeRegistry, so the shell, scenario
// files and genomes can create controllers by name:
//
//   mdl2e   runs an MDL2e program (docs/mdl2e.md)     program, speed_limit, warn_interval
//           defaults: priority 2, period 30 ms (the paper's 33.33 Hz), queue 4
//
// Programs are named, not inlined: `program=obstacle_avoidance.mdl2e` is a reference that
// ControlResources::read_program turns into program text. The control layer opens no files (it
// must build for a microcontroller), so the caller decides what a reference means: a file under a
// scenario folder, an entry of a table compiled into the firmware, a genome's text.
#pragma once

#include <functional>
#include <string>
#include <string_view>

#include "symb/kernel/result.hpp"
#include "symb/os/task_type_registry.hpp"

namespace symb::control {

struct ControlResources {
  // The text of the program `reference` names, or an error saying why not. Called when a task is
  // created, on the creating thread. Missing: every creation fails with an error saying so.
  std::function<kernel::Result<std::string>(std::string_view reference)> read_program;
};

// Adds the types above. Fails (adding nothing more) when a name is already taken. A program that
// cannot be read or compiled makes creation fail with an error naming the reference and, for a
// compile error, its LINE:COLUMN.
kernel::Status register_control_task_types(os::TaskTypeRegistry& registry, ControlResources resources);

}  // namespace symb::control
