// Handles: how tasks and hooks are named across API boundaries. A handle is an index plus a
// generation (tasks) or a serial that is never reused (hooks), so a handle kept after its task was
// deleted and its slot reused simply stops matching: rewiring at runtime never leaves a dangling
// pointer in the caller's hands.
#pragma once

#include <compare>
#include <cstdint>
#include <limits>

namespace symb::os {

struct TaskId {
  std::uint32_t index = std::numeric_limits<std::uint32_t>::max();
  std::uint32_t generation = 0;

  bool valid() const { return index != std::numeric_limits<std::uint32_t>::max(); }
  friend auto operator<=>(const TaskId&, const TaskId&) = default;
};

struct HookId {
  std::uint32_t sender_index = std::numeric_limits<std::uint32_t>::max();
  std::uint32_t serial = 0;

  bool valid() const { return serial != 0; }
  friend auto operator<=>(const HookId&, const HookId&) = default;
};

// A sender's output channel (the paper's "data that should be sent"): receivers may tell
// several outputs of one task apart by port, and a hook may listen to one port only.
using Port = std::uint16_t;

}  // namespace symb::os
