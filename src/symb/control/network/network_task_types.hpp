// Task types for neural networks and ANN circuits (docs/networks.md): the control layer's entries
// in a TaskTypeRegistry, added by register_control_task_types():
//
//   mlp      feed-forward perceptron / MLP     inputs, layers, activation, weights, input_scale, ...
//   elman    Elman recurrent network           the same
//   ctrnn    continuous-time RNN (Beer 1995)   inputs, layers "N O", tau, dt, weights, ...
//   network  any of them from a description    description, weights (override), ...
//
// Weight files and descriptions are references that ControlResources::read_program resolves.
#pragma once

#include "symb/control/control_task_types.hpp"
#include "symb/kernel/result.hpp"
#include "symb/os/task_type_registry.hpp"

namespace symb::control {

// Adds the four types; fails when a name is already taken.
kernel::Status register_network_task_types(os::TaskTypeRegistry& registry, const ControlResources& resources);

}  // namespace symb::control
