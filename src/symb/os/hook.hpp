// Hook: a subscription of a receiver task to a sender task's output (the paper's QueueHookable
// list entry). One send reaches every hooked receiver's queue. Each hook has a priority, a policy
// for a full queue and an enabled flag, and takes part in the two subsumption operations:
//  - suppression: a message delivered through a hook with suppress_window > 0 (or an explicit
//    Node::suppress) blocks delivery through lower-priority hooks into the same receiver for that
//    window: [t, t + window);
//  - inhibition: Node::inhibit blocks a sender's output through its hooks (to one receiver or to
//    all) for a window [t, t + window).
// Both compare the window against the message's send time, so they are exact in virtual time.
#pragma once

#include <cstdint>
#include <string>

#include "symb/kernel/bounded_queue.hpp"
#include "symb/kernel/time.hpp"
#include "symb/os/ids.hpp"

namespace symb::os {

// What a delivery into a full queue does (sensor data keeps the newest; commands refuse).
using QueuePolicy = kernel::FullPolicy;

struct HookOptions {
  int priority = 0;
  QueuePolicy policy = QueuePolicy::kKeepNewest;
  bool enabled = true;
  // When >= 0, only messages on this port travel through the hook.
  std::int32_t port = -1;
  // When > 0, each delivery through this hook suppresses lower-priority hooks into the same
  // receiver for this long.
  kernel::Duration suppress_window{0};
};

// The rule for duplicate hooks, in one place: a hook is known by its sender, its receiver and its
// port (-1, any port, being one value), and a second hook with the same three would deliver
// every message twice. Node::hook refuses it (the shell's `hook`, code); the scenario parser
// refuses it with the file's line.
inline bool same_hook_key(std::int32_t port_a, std::int32_t port_b) {
  return (port_a < 0 ? -1 : port_a) == (port_b < 0 ? -1 : port_b);
}

struct HookInfo {
  HookId id;
  TaskId sender;
  TaskId receiver;
  std::string sender_name;
  std::string receiver_name;
  HookOptions options;
  kernel::Time inhibited_until{0};
};

const char* to_string(QueuePolicy p);

}  // namespace symb::os
