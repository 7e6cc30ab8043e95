// Hook: a subscription of a receiver task to a sender task's output (the paper's QueueHookable
// list entry). One send reaches every hooked receiver's queue. Each hook has a priority, a policy
// for a full queue and an enabled flag, and takes part in the two subsumption operations:
//  - suppression: a message delivered through a hook with suppress_window > 0 (or an explicit
//    Node::suppress) blocks delivery through lower-priority hooks into the same receiver for that
//    window: [t, t + window);
//  - inhibition: Node::inhibit blocks a sender's output through its hooks (to one receiver or to
//    all) for a window [t, t + window).
// Both compare the window against the message's send time, so they are exact in virtual time.
//
// Accounting per hook (an edge sender -> receiver), checked exactly by tests/os, at every moment:
//   sent      == skipped + attempted                   every send of the sender while hooked
//   attempted == delivered + dropped() + queued        every message offered to the receiver
// where `sent` counts the sender's sends since the hook was made, `skipped` those the hook let
// pass (disabled, another port), and the rest is the receiver's TrafficCounters for this hook
// only. Node::hooks() gives it per live hook, Node::hook_traffic() summed over every hook the node
// ever had.
//
// Cycles: a hook may close a cycle (a -> b -> a). What bounds it is kMaxHops (message.hpp): a
// chain of answers longer than that faults the task that would extend it.
//
// A hook's receiver may also be outside the node (HookSink below: a writer to a network), and a
// source outside the node may send as a task standing for it (Node::send_as): both let a
// message leave or enter a node with no hand-over to another task's thread.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <utility>

#include "symb/kernel/bounded_queue.hpp"
#include "symb/kernel/time.hpp"
#include "symb/os/ids.hpp"
#include "symb/os/task.hpp"

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

// One hook's accounting, or a sum of several (see the top of this file).
struct HookTraffic {
  std::uint64_t sent = 0;     // the sender's sends while hooked
  std::uint64_t skipped = 0;  // of those, not offered (disabled, another port)
  TrafficCounters traffic;    // offered to the receiver through the hook, and what became of them
  std::uint64_t queued = 0;   // in the receiver's queue now

  // Both equations hold.
  bool closes() const {
    return sent == skipped + traffic.attempted && traffic.attempted == traffic.delivered + traffic.dropped() + queued;
  }
  HookTraffic& operator+=(const HookTraffic& o) {
    sent += o.sent;
    skipped += o.skipped;
    traffic += o.traffic;
    queued += o.queued;
    return *this;
  }
};

// The rule for duplicate hooks, in one place: a hook is known by its sender, its receiver and its
// port (-1, any port, being one value), and a second hook with the same three would deliver
// every message twice. Node::hook refuses it (the shell's `hook`, code); the scenario parser
// refuses it with the file's line.
inline bool same_hook_key(std::int32_t port_a, std::int32_t port_b) {
  return (port_a < 0 ? -1 : port_a) == (port_b < 0 ? -1 : port_b);
}

// The far end of a hook whose receiver is not a task of the node: a writer to a network, a
// recorder (Node::hook(sender, sink, options)). It is handed each message the hook lets through
// on the sender's own context, within the sender's send(), after the node's locks are released:
// no queue, no hand-over to another thread. Of the hook's options, the port filter, the enabled
// flag, inhibition and the priority (the order among the sender's hooks) apply; a queue policy
// and a suppression window, which belong to a receiver's queue, do not. Its accounting: every
// message offered is delivered (handed to the sink) or inhibited, none is queued.
// on_message must not block; it runs on whichever thread sent, so a sender fed by
// Node::send_as from several threads calls it from several at once. The node holds a reference
// while the hook lives and during a call: a send counted before an unhook may still call it just
// after the unhook returned.
class HookSink {
 public:
  explicit HookSink(std::string name) : name_(std::move(name)) {}
  virtual ~HookSink() = default;
  HookSink(const HookSink&) = delete;
  HookSink& operator=(const HookSink&) = delete;
  // What Node::hooks() shows as the hook's receiver.
  const std::string& name() const { return name_; }
  virtual void on_message(const Message& m) = 0;

 private:
  const std::string name_;
};

struct HookInfo {
  HookId id;
  TaskId sender;
  TaskId receiver;  // invalid for a hook to a HookSink
  std::string sender_name;
  std::string receiver_name;       // the sink's name for a hook to a HookSink
  std::shared_ptr<HookSink> sink;  // that sink (to hook it again elsewhere); null for a task
  HookOptions options;
  kernel::Time inhibited_until{0};
  HookTraffic accounting;
};

const char* to_string(QueuePolicy p);

}  // namespace symb::os
