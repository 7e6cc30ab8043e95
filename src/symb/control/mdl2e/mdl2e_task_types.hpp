// Task types for MDL2e controllers: the control layer's entries in a TaskTypeRegistry, added by
// register_control_task_types(). See docs/mdl2e.md, "The controller task", for the type and its
// parameters.
#pragma once

#include "symb/control/control_task_types.hpp"
#include "symb/kernel/result.hpp"
#include "symb/os/task_type_registry.hpp"

namespace symb::control {

kernel::Status register_mdl2e_task_types(os::TaskTypeRegistry& registry, const ControlResources& resources);

}  // namespace symb::control
