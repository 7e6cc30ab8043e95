// Task types for organisms of docked modules (roles, leadership of a service): the control
// layer's entries in a TaskTypeRegistry, added by register_control_task_types(). See
// docs/organism.md.
#pragma once

#include "symb/control/control_task_types.hpp"
#include "symb/kernel/result.hpp"
#include "symb/os/task_type_registry.hpp"

namespace symb::control {

kernel::Status register_organism_task_types(os::TaskTypeRegistry& registry, const ControlResources& resources);

}  // namespace symb::control
