// Port layouts: what the numbers of a message on one port mean, so that a hook between two task
// types that disagree (a [left, right] wheel command into a task that reads an IR vector on that
// port) is refused when it is made, naming both ends and both layouts, instead of being a silent
// mismatch. A task type declares its input and output ports (TaskType::inputs, outputs); a task
// made in code declares none and is never checked. The layouts themselves are a catalogue in the
// layer that defines the messages (robot/ports.hpp); here is only what the check needs.
#pragma once

#include <string_view>
#include <vector>

#include "symb/os/ids.hpp"

namespace symb::os {

// A message shape, named for errors. Layouts are compared by name; "any" matches every layout
// (a task that forwards whatever its device has, one number per channel).
struct PortLayout {
  std::string_view name;
  std::string_view doc;
};

inline constexpr PortLayout kAnyLayout{"any", "any numbers"};

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
inline const PortSpec* find_port(const std::vector<PortSpec>& ports, Port port) {
  for (const auto& p : ports)
    if (p.port == port) return &p;
  return nullptr;
}

}  // namespace symb::os
