// Control task types: the control layer's entries in a TaskTypeRegistry, so the shell, scenario
// files and genomes can create controllers by name. Each family registers its own types from its
// folder (mdl2e/, ahhs/, network/, subsumption/, schemas/, snn/: `<family>_task_types`, with the
// types and parameters in the family's doc); register_control_task_types() adds them all.
//
// Programs are named, not inlined: `program=obstacle_avoidance.mdl2e` is a reference that
// ControlResources::read_program turns into program text. The control layer opens no files (it
// must build for a microcontroller), so the caller decides what a reference means: a file under a
// scenario folder, an entry of a table compiled into the firmware, a genome's text.
#pragma once

#include <functional>
#include <string>
#include <string_view>

#include "symb/io/device.hpp"
#include "symb/kernel/result.hpp"
#include "symb/os/task_type_registry.hpp"

namespace symb::control {

struct ControlResources {
  // The text of the program `reference` names, or an error saying why not. Called when a task is
  // created, on the creating thread. Missing: every creation fails with an error saying so.
  std::function<kernel::Result<std::string>(std::string_view reference)> read_program;
  // The robot's device called `name` (an MDL2e program's `device NAME COMMAND` actions), or null.
  // Missing: a robot without devices; every device action fails with a warning.
  std::function<std::shared_ptr<io::Device>(std::string_view name)> device;
};

// A reference as errors quote it: cut after 120 characters, so a program pasted whole into a
// parameter does not flood the reply.
std::string shown_reference(std::string_view reference);

// Adds the types above. Fails (adding nothing more) when a name is already taken. A program that
// cannot be read or compiled makes creation fail with an error naming the reference and, for a
// compile error, its LINE:COLUMN.
kernel::Status register_control_task_types(os::TaskTypeRegistry& registry, ControlResources resources);

}  // namespace symb::control
