#include "symb/control/subsumption/subsumption_rewiring.hpp"

#include <vector>

namespace symb::control {

kernel::Result<os::TaskId> add_layer(os::Node& node, std::string_view type, std::string name,
                                     std::span<const os::ParamAssignment> params, std::span<const os::TaskId> inputs,
                                     os::TaskId receiver, int priority, kernel::Duration suppress_window) {
  auto id = node.create(type, std::move(name), params);
  if (!id) return kernel::Error{id.error()};
  auto undo = [&](const std::string& why) -> kernel::Result<os::TaskId> {
    (void)node.remove(*id);
    return kernel::Error{why};
  };
  for (os::TaskId in : inputs)
    if (auto h = node.hook(in, *id); !h) return undo(h.error());
  os::HookOptions out;
  out.priority = priority;
  out.suppress_window = suppress_window;
  if (auto h = node.hook(*id, receiver, out); !h) return undo(h.error());
  return *id;
}

kernel::Status replace_task(os::Node& node, os::TaskId old_task, os::TaskId replacement) {
  if (old_task == replacement) return kernel::Error{"a task cannot replace itself"};
  if (!node.info(old_task)) return kernel::Error{"no task to replace"};
  if (!node.info(replacement)) return kernel::Error{"no replacement task"};
  std::vector<os::HookId> made;
  for (const os::HookInfo& h : node.hooks()) {
    kernel::Result<os::HookId> r = kernel::Error{""};
    if (h.sender == old_task && h.sink) {
      r = node.hook(replacement, h.sink, h.options);  // a hook out of the node (a DDS writer)
    } else if (h.sender == old_task && h.receiver != replacement) {
      r = node.hook(replacement, h.receiver, h.options);
    } else if (h.receiver == old_task && h.sender != replacement) {
      r = node.hook(h.sender, replacement, h.options);
    } else {
      continue;
    }
    if (!r) {
      for (os::HookId m : made) (void)node.unhook(m);
      return kernel::Error{"hook " + h.sender_name + " -> " + h.receiver_name + ": " + r.error()};
    }
    made.push_back(*r);
  }
  return node.remove(old_task);
}

}  // namespace symb::control
