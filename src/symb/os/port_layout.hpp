// Port layouts: what the numbers of a message on one port mean, so that a hook between two task
// types that disagree (a [left, right] wheel command into a task that reads an IR vector on that
// port) is refused when it is made, naming both ends and both layouts, instead of being a silent
// mismatch. A task type declares its input and output ports (TaskType::inputs, outputs); a task
// may also be given its own declaration when it is created (TaskOptions::ports): a task made in
// code, or a generic device task whose layout depends on its device (a sensor task reading the IR
// ring sends a sensor vector, one reading the pose sends a pose). A task with neither is never
// checked. The layouts themselves are a catalogue in the layer that defines the messages
// (robot/ports.hpp); here is only what the check needs, and the one check that Node::hook and
// development (evo/embryogenesis) both apply.
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "symb/kernel/result.hpp"
#include "symb/os/ids.hpp"

namespace symb::os {

// A message shape, named for errors. Layouts are compared by name; "any" matches every layout
// (a task that forwards whatever its device has, one number per channel).
struct PortLayout {
  std::string_view name;
  std::string_view doc;
};

inline constexpr PortLayout kAnyLayout{"any", "any numbers"};
// The input of a task that reads no messages (a sensor task): only a sender of `any` matches it.
inline constexpr PortLayout kNoMessages{"none", "nothing: the task reads no messages"};

inline bool compatible(const PortLayout& a, const PortLayout& b) {
  return a.name == kAnyLayout.name || b.name == kAnyLayout.name || a.name == b.name;
}

// One port of a task type: its number, its role's name and its layout.
struct PortSpec {
  Port port = 0;
  std::string_view name;
  PortLayout layout = kAnyLayout;
};

// The declared port `port` of `ports`, or null.
inline const PortSpec* find_port(std::span<const PortSpec> ports, Port port) {
  for (const auto& p : ports)
    if (p.port == port) return &p;
  return nullptr;
}

// The ports one task declares: a task type's, or a creator's own (TaskOptions::ports).
struct PortDeclaration {
  std::vector<PortSpec> inputs;
  std::vector<PortSpec> outputs;
};

// One end of a hook as the layout check sees it: the task's name, its type's name ("-" for a task
// made in code) and its declared ports.
struct PortEnd {
  std::string_view task;
  std::string_view type;
  std::span<const PortSpec> inputs;
  std::span<const PortSpec> outputs;
};

// The rule of every hook: on each port the hook carries (`port`, or all when it is negative), a
// layout the sender declares as an output and the layout the receiver declares as an input on the
// same port number must be compatible; and a hook on one port of a sender that declares its
// outputs must name one of them (it would carry nothing). A port the receiver leaves undeclared,
// and a sender that declares no outputs, are not checked. The error names both tasks, their
// types, the port and both layouts.
inline kernel::Status check_layouts(const PortEnd& sender, const PortEnd& receiver, int port) {
  if (port >= 0 && !sender.outputs.empty() && find_port(sender.outputs, static_cast<Port>(port)) == nullptr) {
    std::string declared;
    for (const PortSpec& out : sender.outputs)
      declared += (declared.empty() ? "" : ", ") + std::to_string(out.port) + " (" + std::string(out.layout.name) + ")";
    return kernel::Error{"cannot hook '" + std::string(sender.task) + "' (" + std::string(sender.type) + ") to '" +
                         std::string(receiver.task) + "' (" + std::string(receiver.type) + ") on port " +
                         std::to_string(port) + ": '" + std::string(sender.task) + "' sends on port " + declared +
                         " only"};
  }
  for (const PortSpec& out : sender.outputs) {
    if (port >= 0 && out.port != port) continue;
    const PortSpec* in = find_port(receiver.inputs, out.port);
    if (in == nullptr || compatible(out.layout, in->layout)) continue;
    const auto str = [](std::string_view v) { return std::string(v); };
    return kernel::Error{"cannot hook '" + str(sender.task) + "' (" + str(sender.type) + ") to '" + str(receiver.task) +
                         "' (" + str(receiver.type) + "): port " + std::to_string(out.port) + " carries " +
                         str(out.layout.name) + " (" + str(out.layout.doc) + ") out of '" + str(sender.task) +
                         "', but '" + str(receiver.task) + "' reads " + str(in->layout.name) + " (" +
                         str(in->layout.doc) + ") there"};
  }
  return {};
}

// A creator's declaration must agree with the type's: on every port both declare in the same
// direction the layouts are compatible (a creator narrows a type's `any`, never contradicts it).
inline kernel::Status check_declaration_fits(const PortDeclaration& own, const PortEnd& type) {
  const auto fits = [&](std::span<const PortSpec> mine, std::span<const PortSpec> theirs,
                        const char* direction) -> kernel::Status {
    for (const PortSpec& p : mine)
      if (const PortSpec* t = find_port(theirs, p.port); t && !compatible(p.layout, t->layout))
        return kernel::Error{std::string(direction) + " port " + std::to_string(p.port) + " declared " +
                             std::string(p.layout.name) + ", but type '" + std::string(type.type) + "' declares " +
                             std::string(t->layout.name) + " there"};
    return {};
  };
  if (auto st = fits(own.inputs, type.inputs, "input"); !st) return st;
  return fits(own.outputs, type.outputs, "output");
}

}  // namespace symb::os
