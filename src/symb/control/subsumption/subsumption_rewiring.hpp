// Dynamic subsumption (paper section III-A): layers added, removed and replaced while the robot
// runs. Adding is Node::create + Node::hook with the layer's hook priority and suppress window;
// removing is Node::remove (its hooks go with it). Replacing must keep the layer's place in the
// stack: the new task takes over every hook of the old one (same options: priority, suppress
// window, policy, port), in both directions, before the old one is removed, so no lower layer
// gets through in between.
#pragma once

#include <span>
#include <string>
#include <string_view>

#include "symb/kernel/result.hpp"
#include "symb/os/hook.hpp"
#include "symb/os/ids.hpp"
#include "symb/os/node.hpp"
#include "symb/os/param.hpp"

namespace symb::control {

// Creates a layer of a registered type named `name` and hooks it into `receiver` (the wheels) with
// `priority` and `suppress_window`; `inputs` are hooked into it (sensors).
kernel::Result<os::TaskId> add_layer(os::Node& node, std::string_view type, std::string name,
                                     std::span<const os::ParamAssignment> params, std::span<const os::TaskId> inputs,
                                     os::TaskId receiver, int priority, kernel::Duration suppress_window);

// Gives `replacement` every hook `old_task` has (in and out, same options), then removes
// `old_task`. On an error nothing is removed (hooks made so far are undone).
kernel::Status replace_task(os::Node& node, os::TaskId old_task, os::TaskId replacement);

}  // namespace symb::control
