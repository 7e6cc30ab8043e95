// Task: one reactive unit of a robot's control system (the paper's Task class). A task never
// blocks or sleeps: its node's executor calls its handlers (start, message, tick, notify, stop) one at a
// time, on the task's own execution context, and the task answers by sending messages to the
// tasks hooked to it. State: created -> running <-> suspended -> deleted, or faulted when a
// handler throws (that task only; the rest of the node goes on).
#pragma once

#include <cstdint>
#include <initializer_list>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "symb/kernel/clock.hpp"
#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"
#include "symb/os/ids.hpp"
#include "symb/os/message.hpp"
#include "symb/os/param.hpp"
#include "symb/os/param_table.hpp"
#include "symb/os/port_layout.hpp"
#include "symb/os/syslog.hpp"

namespace symb::os {

class Node;
namespace detail {
struct TaskRecord;
}

enum class TaskState : std::uint8_t { kCreated, kRunning, kSuspended, kFaulted, kDeleted };
const char* to_string(TaskState s);

struct TaskOptions {
  int priority = 0;
  kernel::Duration period{0};  // 0: never ticked
  std::size_t queue_capacity = 16;
  bool autostart = true;  // false: stays `created` until Node::start()
  // This task's own port layouts (see port_layout.hpp), checked by every hook it takes part in.
  // Unset: a task of a registered type has its type's, a task made in code none. A task of a type
  // may only narrow the type's declaration (a sensor task that reads the IR ring sends a sensor
  // vector where its type says any), never contradict it.
  std::optional<PortDeclaration> ports = std::nullopt;
};

// Message accounting for one receiver. For every receiver, at every moment:
// attempted == delivered + dropped() + queued.
struct TrafficCounters {
  std::uint64_t attempted = 0;    // messages offered to the receiver's queue
  std::uint64_t delivered = 0;    // handed to its on_message()
  std::uint64_t overwritten = 0;  // pushed out of a full queue by a newer one (keep-newest hooks)
  std::uint64_t refused = 0;      // refused by a full queue (refuse hooks)
  std::uint64_t suppressed = 0;   // dropped by a suppression window
  std::uint64_t inhibited = 0;    // dropped by an inhibition window
  std::uint64_t discarded = 0;    // still queued when the task was deleted

  std::uint64_t dropped() const { return overwritten + refused + suppressed + inhibited + discarded; }
  TrafficCounters& operator+=(const TrafficCounters& o);
};

struct TaskInfo {
  TaskId id;
  std::string name;
  std::string type;  // the registered type's name, or "-" for a task made in code
  TaskState state = TaskState::kCreated;
  int priority = 0;
  kernel::Duration period{0};
  std::size_t queue_depth = 0;
  std::size_t queue_capacity = 0;
  std::uint64_t sent = 0;  // send() calls
  TrafficCounters traffic;
};

class Task {
 public:
  Task() = default;
  virtual ~Task() = default;
  Task(const Task&) = delete;
  Task& operator=(const Task&) = delete;

  // A hint for the executor, with no effect on behaviour (kernel::Activity::prefetch): asks the
  // memory system for what this task's next handler reads beyond the object's first two cache
  // lines. Level 0 (those two lines already asked for): the rest of a large object, or the device
  // a member points to; level 1, a while later: what those point to. Called on the task's own
  // context; the default asks for nothing.
  virtual void prefetch(int /*level*/) const {}

 protected:
  virtual void on_start() {}
  virtual void on_message(const Message& /*message*/) {}
  virtual void on_tick() {}
  // Node::notify woke the task (once for any number of notifications since it last ran).
  virtual void on_notify() {}
  virtual void on_stop() {}
  // A live parameter (ParamTable's .live()) was just written into the options this task bound
  // (bind_parameters), on this task's own context. Recompute what depends on it here, or refuse
  // the value: the options are then put back and the error is the change's reply (logged).
  virtual kernel::Status on_parameter_changed(std::string_view /*name*/) { return {}; }

  // Declares, from the constructor, that this task takes its messages at once: under a
  // non-concurrent executor (virtual time, lockstep) a message another task sends it from a
  // handler is handed to on_message before that send() returns, once the send has reached every
  // hook, with no queue and no activation of its own. Only when its queue is empty and it is not
  // inside a handler already; otherwise, and under the thread executor, and for a send from
  // outside any handler (Node::send_as, Node::post), the message is queued as usual. For a task
  // whose on_message only acts on a device, as the paper's standard actuator "changes the robot's
  // state immediately", or turns a reading into a command (a controller): at a robot's every
  // step that spares a queue round trip and an event per message. The message is the one a queue
  // would hand over (time, source, hops), counted as one (accounting, suppression, tracing), and
  // a throw faults the task as it would. What such a task sends from on_message goes out from
  // within its sender's send; a chain of such tasks is cut to a queue at Node::kMaxImmediateDepth.
  void take_messages_at_once() { immediate_ = true; }
  // Declares, from the constructor, that this task takes its notifications at once: under a
  // non-concurrent executor, a notify() made from inside another activity's handler on the
  // executor's own context (a simulated device publishing from the world's step) runs on_notify
  // before notify returns, with no activation of its own, when the task is idle (not inside a
  // handler, nothing queued, no parameters waiting, running, the nesting below
  // Node::kMaxImmediateDepth) and no event due at this instant comes before its activation would;
  // otherwise (and through Node::notify, which holds the node's lock) it is woken as usual. The one
  // difference from a wake: on_notify comes before the rest of the notifying handler, not after
  // it. For a task whose on_notify only drains a device into messages (SensorTask): at a robot's
  // every step that spares an event and a wake. The caller must hold no lock on_notify takes (a
  // device's own data lock): a SensorTask asks for this only for a device called one context at a
  // time, which has none.
  void take_notifications_at_once() { immediate_notify_ = true; }

  // Declares where this task keeps its parameters: `options`, a member of the task, whose type is
  // the config struct of its type's ParamTable or one of that struct's bases. A running task's
  // live parameters are written there. Call from the constructor.
  template <class Options>
  void bind_parameters(Options& options) {
    if (!bindings_) bindings_ = std::make_unique<std::vector<Binding>>();
    bindings_->push_back({detail::type_tag<Options>(), &options});
  }

  // Services for handlers; valid from on_start() until on_stop() returns.
  Node& node() const;
  TaskId id() const;
  const std::string& name() const;
  kernel::Time now() const { return clock_->read(); }
  // Messages waiting in this task's own queue (a tick may leave its work to one of them). Cheap: no
  // copy, and a lock only under the thread executor.
  std::size_t pending_messages() const;
  // From a handler: this task's ticks before `t` would do nothing (kernel::ActivitySlot::
  // skip_ticks_before), so the executor may leave them out; the next tick is then the first one of
  // the period's grid at or after `t`. For a deadline checked at ticks (a watchdog) that moves
  // with the traffic, or a tick of this instant that new input has made idle (a controller that
  // just stepped): what the task does is the same, with fewer activations. Returns how many
  // ticks already due before `t` were left out by this call, for the task to count.
  std::uint64_t skip_ticks_before(kernel::Time t);
  // Sends to every task hooked to this one. Timestamped with the node clock.
  void send(Port port, const Payload& payload);
  void send(Port port, std::span<const float> values);
  void send(Port port, std::initializer_list<float> values) { send(port, std::span<const float>(values)); }
  void log(LogLevel level, std::string_view text) const;
  // Node::notify(id()) without finding the task first: for a notifier the task attached in
  // on_start and detaches in on_stop (a device saying its data is ready, thousands of times a
  // step in a swarm), which may call it until then. The threads it may come from are
  // Node::notify's.
  void notify();
  // Hands a sample of this task's internal state to the node's probe sink (Node::set_probe_sink),
  // e.g. probe("hormones/c0", levels). Channel names are the task's own; keep them few and fixed
  // so a recorder can make one plot per channel. Nothing happens without a sink.
  void probe(std::string_view channel, std::span<const float> values) const;
  void probe(std::string_view channel, std::initializer_list<float> values) const {
    probe(channel, std::span<const float>(values.begin(), values.size()));
  }
  // Whether a sink listens: skip gathering state nobody will see.
  bool probing() const;
  // This task's own random stream, derived from the node seed and the task's name.
  kernel::RandomStream& random();

 private:
  friend class Node;
  friend struct detail::TaskRecord;
  // A parameter changed at runtime (shell, scenario, genome); the value has passed the schema's
  // type and range check. Runs on the task's own context: writes a live parameter through its
  // type's declaration into the bound options, then on_parameter_changed(); refuses the others.
  kernel::Status on_parameter(std::string_view name, const ParamValue& value);

  struct Binding {
    const void* owner = nullptr;
    void* object = nullptr;
  };
  detail::TaskRecord* record_ = nullptr;
  const kernel::Clock* clock_ = nullptr;  // the node's, set with record_: now() is in line
  bool immediate_ = false;                // take_messages_at_once()
  bool immediate_notify_ = false;         // take_notifications_at_once()
  // A pointer, not the vector: most tasks bind nothing, and 16 bytes a task count in a swarm.
  std::unique_ptr<std::vector<Binding>> bindings_;
};

}  // namespace symb::os
