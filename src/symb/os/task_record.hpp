// TaskRecord: the node's private bookkeeping for one task (not part of the public API): its
// queue, hooks, counters and state, and its side of the executor contract. Kept in its own header
// only so that node.cpp and task.cpp share one definition.
#pragma once

#include <array>
#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "symb/kernel/executor.hpp"
#include "symb/kernel/optional_mutex.hpp"
#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/ring_buffer.hpp"
#include "symb/os/hook.hpp"
#include "symb/os/message.hpp"
#include "symb/os/task.hpp"
#include "symb/os/task_type_registry.hpp"

namespace symb::os::detail {

struct TaskRecord;

// The far end of a hook to a HookSink, with the hook's traffic (there is no receiver to count
// it). Owned by its Hook, under the sender's out_mu; freed by Node::end_hook.
struct SinkEnd {
  std::shared_ptr<HookSink> sink;
  TrafficCounters traffic;
  bool due = false;  // to be handed the message being sent, once out_mu is released
};

// One entry of a sender's hook list. The receiver pointer is safe: a task is unhooked from every
// sender, under that sender's out_mu, before it can be freed. Its traffic is counted at the
// receiver (InHook, slot `edge` - 1), except what never reaches the receiver: the sends it let
// pass (disabled, another port), counted here under out_mu. A hook to a HookSink has no receiver
// task: it holds its SinkEnd in the receiver's place (`to_sink`), so a hook stays 64 bytes.
struct Hook {
  std::uint32_t serial = 0;
  std::uint32_t edge = 0;         // the receiver's InputHooks slot + 1 (0 for a sink)
  std::uint64_t sent_before = 0;  // the sender's `sent` when the hook was made
  std::uint64_t skipped = 0;      // sends not offered: disabled, or another port
  std::int32_t priority = 0;
  std::int32_t port = -1;
  QueuePolicy policy = QueuePolicy::kKeepNewest;
  bool enabled = true;
  bool to_sink = false;
  union {
    TaskRecord* receiver = nullptr;  // unless to_sink
    SinkEnd* sink;                   // to_sink
  };
  kernel::Duration suppress_window{0};
  kernel::Time inhibited_until{0};

  // The receiving task, or null for a hook to a sink.
  TaskRecord* task() const { return to_sink ? nullptr : receiver; }
};

// A hook's accounting at its receiver, under the receiver's in_mu. Every message it queues is
// tagged with the slot (Message::edge), so its fate (handled, overwritten, discarded) is counted
// here too. When the hook goes, `sent` and `skipped` are copied from the sender's side; the slot
// is freed (its counts folded into InputHooks::retired) once none of its messages is queued.
struct InHook {
  std::uint32_t serial = 0;  // 0: a free slot
  bool hooked = false;
  std::uint64_t sent = 0;     // valid once !hooked
  std::uint64_t skipped = 0;  // valid once !hooked
  TrafficCounters traffic;

  std::uint64_t in_flight() const { return traffic.attempted - traffic.delivered - traffic.dropped(); }
};

// A suppression in force at a receiver: hooks below `level` are blocked until `until`.
struct SuppressionWindow {
  std::int32_t level = 0;
  kernel::Time until{0};
};

// The input side of a task that has (or had) hooks into it or a suppression window, under in_mu.
// Made when the first is needed: a task nothing is hooked into does without these bytes.
struct InputHooks {
  // Per hook into the task (see InHook), slot i at(i). The first kInlineSlots live here, beside
  // the windows: every delivery counts against its slot, and most tasks have one or two hooks into
  // them, so the counters are in the block the delivery reads anyway instead of one more (in a
  // swarm, a cache miss per message).
  static constexpr std::size_t kInlineSlots = 2;
  std::array<InHook, kInlineSlots> inline_slots{};
  std::vector<InHook> more_slots;
  std::uint32_t slot_count = 0;
  std::vector<std::uint32_t> free_slots;  // free slots below slot_count
  HookTraffic retired;                    // hooks into the task whose slot was freed
  std::array<SuppressionWindow, 2> suppression{};

  // The window to use for `level` at `now`: the one of this level, else one that has ended, else
  // the one that ends first.
  SuppressionWindow& window_for(int level, kernel::Time now);
  InHook& at(std::uint32_t i) { return i < kInlineSlots ? inline_slots[i] : more_slots[i - kInlineSlots]; }
  const InHook& at(std::uint32_t i) const { return i < kInlineSlots ? inline_slots[i] : more_slots[i - kInlineSlots]; }
  // A new slot at the end; returns its index.
  std::uint32_t add_slot() {
    if (slot_count >= kInlineSlots) more_slots.emplace_back();
    return slot_count++;
  }
};

// Parameter state of a task made from a registered type.
struct ParamState {
  const TaskType* type = nullptr;
  ParamSet values;
  std::vector<std::pair<std::string, ParamValue>> pending;  // applied on the task's context
};

struct TaskRecord final : kernel::Activity {
  TaskRecord(Node& n, TaskId i, std::string nm, std::unique_ptr<Task> t, const TaskOptions& o, bool concurrent);

  void on_activity_attached(kernel::ActivitySlot& s) override;
  void on_activity_start() override;
  void on_activity_input() override;
  void on_activity_tick() override;
  void on_activity_stop() override;
  void on_activity_released() override;
  void prefetch(int level) const override;

  // Offers `m` to this task's queue through hook slot `edge` (0: posted); returns the slot to
  // wake (outside any lock) or null. `*accepted` (when given) tells whether the message was queued.
  // Inline, defined [[gnu::always_inline]] in node.cpp (its only user): see Node::send_locked.
  inline kernel::ActivitySlot* offer(const Message& m, std::uint32_t edge, int priority, QueuePolicy policy,
                                     kernel::Duration suppress_window, bool* accepted = nullptr);
  // For a task that takes messages at once (`immediate`), from inside a handler of the sender
  // (Node::send_locked): whether it may be handed a message now (not inside a handler, nothing
  // queued, no notification or parameters waiting, running, the nesting below its bound); if so
  // the send admits the message (admit) and, once every hook has had it, calls take_now, which
  // hands it to on_message, or queues it if the receiver can no longer take it.
  bool can_take_now() const;
  void take_now(const Message& m, std::uint32_t edge, QueuePolicy policy);
  // The queue's side of offer, after admit: returns the slot to wake, or null.
  inline kernel::ActivitySlot* enqueue(const Message& m, std::uint32_t edge, QueuePolicy policy, InHook* e,
                                       bool* accepted = nullptr);
  // The accounting and suppression every message offered goes through first: false when a
  // suppression window drops it (counted). Under in_mu.
  inline bool admit(const Message& m, InHook* e, int priority, kernel::Duration suppress_window);
  // What every handled message does around on_message: its hops, chain trail, trace.
  inline void handle_message(const Message& m);
  // Under in_mu: the counters of hook slot `edge` (0: none).
  InHook* in_hook(std::uint32_t edge) { return edge == 0 ? nullptr : &inputs->at(edge - 1); }
  // Under in_mu: the input side's hook slots and windows, made on first use.
  InputHooks& input_hooks() {
    if (!inputs) inputs = std::make_unique<InputHooks>();
    return *inputs;
  }
  // Under in_mu: a slot for a new hook into this task; returns its `edge`.
  std::uint32_t add_in_hook(std::uint32_t serial);
  // Under in_mu: the hook of slot `edge` is gone; `sent` and `skipped` from the sender's side.
  void end_in_hook(std::uint32_t edge, std::uint64_t sent, std::uint64_t skipped);
  // Under in_mu: frees the slot when the hook is gone and none of its messages is queued.
  void retire_in_hook_if_done(std::uint32_t edge);
  // Node::notify's work once the task is found: on_notify() is due, and the task is woken; or,
  // when `may_run_here` (the caller holds no node lock: Task::notify), for a task that takes
  // notifications at once and can now (its slot can run inline), on_notify() runs here.
  void notify(bool may_run_here);
  // notify's at-once path: on_notify() now, as an activation would run it.
  void take_notification_now();
  void fault(const char* where, const char* what);
  // Every handler starts here: the test in line, the work (rare) out of line. `params` is set
  // before the task starts and never replaced, so the unlocked test is safe and spares the common
  // case (no parameters) a lock per batch.
  void apply_pending_parameters() {
    if (params_pending.load(std::memory_order_acquire)) apply_parameters_now();
  }
  void apply_parameters_now();

  // Hot fields first, in the order a delivery and a handler read them: being handed a message and
  // handling it reads the record's first 168 bytes, sending the 40 after them, and the rest is for
  // the shell and rare paths. In a swarm every record is out of the cache at each step, so each
  // cache line of it that a step reads is a miss. hot_bytes() is what prefetch asks for.
  Node& node;
  std::unique_ptr<Task> task;
  kernel::ActivitySlot* slot = nullptr;  // set under in_mu
  const TaskId id;
  std::atomic<TaskState> state{TaskState::kCreated};
  // Set with every push to params->pending: every handler tests it, without a lock, here in the
  // record rather than behind `params` (one cache line fewer per handler in a large swarm).
  std::atomic<bool> params_pending{false};
  // Hops of what this task sends now (see kMaxHops): the handled message's + 1 inside
  // on_message, 0 elsewhere. The task's own context only.
  std::uint16_t next_hops = 0;
  // The longest chain this task handled (most hops); see deep_source. Its own context only.
  std::atomic<std::uint16_t> longest_chain{0};

  // Input side, under in_mu.
  bool wake_pending = false;
  bool notified = false;  // Node::notify: on_notify() is due
  // Task::take_messages_at_once under a non-concurrent executor: see take_now.
  const bool immediate;
  // Task::take_notifications_at_once under a non-concurrent executor: see notify.
  const bool immediate_notify;
  // Admitted a message that take_now will hand over later in the same send.
  bool taking_now = false;
  // A handler of this task is running: the guard of take_now, and what lets this task's sends
  // be taken at once (a send from outside any handler, Node::send_as, is queued). Its own
  // context only.
  bool in_handler = false;
  kernel::OptionalMutex in_mu;
  std::unique_ptr<InputHooks> inputs;  // see input_hooks()
  kernel::RingBuffer<Message> queue;
  std::atomic<std::uint64_t> delivered{0};  // written by the task's own context only
  TrafficCounters traffic;                  // `delivered` is mirrored from `delivered` above when read

  // Output side: the hooks of this task as a sender.
  kernel::OptionalMutex out_mu;
  std::atomic<std::uint64_t> sent{0};  // written under out_mu (its own sends, and Node::send_as)
  std::vector<Hook> hooks;

  // Cold: read by the shell, the node's queries and rare paths.
  std::atomic<int> priority;
  std::atomic<std::int64_t> period_ns;
  std::unique_ptr<ParamState> params;
  // Checked by every hook (port_layout.hpp); null: unchecked.
  const std::unique_ptr<const PortDeclaration> ports;
  // The source of the last message this task handled that was more than half way to kMaxHops:
  // with longest_chain, the trail that names a cycle. Written by the task's own context only.
  std::atomic<std::uint64_t> deep_source{~std::uint64_t{0}};
  const std::string name;
  kernel::RandomStream random;

  // The bytes from the record's start that deliveries and handlers read (prefetch asks for these).
  std::size_t hot_bytes() const {
    return static_cast<std::size_t>(reinterpret_cast<const char*>(&hooks + 1) - reinterpret_cast<const char*>(this));
  }
};

}  // namespace symb::os::detail
