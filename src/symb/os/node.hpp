// Node: one robot's operating-system instance (the paper's TaskManager, one per robot instead of
// a process-wide singleton). It owns the robot's tasks and their hooks, its SysLog and its random
// streams, and reads time from the clock of the executor it runs on. Every operation may be
// called at runtime from any task's handler or from outside (a shell, a scenario, a test). Under
// the thread executor that is any thread; under the single-threaded virtual-time executor it is
// the executor's own thread (handlers, or between run_*() calls), and other threads go through
// inject(). Tasks and hooks are named by handles, so rewiring never leaves a dangling reference.
// Hooks join tasks of the same node.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "symb/kernel/executor.hpp"
#include "symb/kernel/optional_mutex.hpp"
#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/result.hpp"
#include "symb/os/hook.hpp"
#include "symb/os/ids.hpp"
#include "symb/os/message.hpp"
#include "symb/os/syslog.hpp"
#include "symb/os/task.hpp"
#include "symb/os/task_type_registry.hpp"

namespace symb::os {

namespace detail {
struct TaskRecord;
struct Hook;
struct TaskSlot {
  std::unique_ptr<TaskRecord> record;
  std::uint32_t generation = 0;
};
}  // namespace detail

// One sample of a task's internal state (hormone levels, activations, the active layer...), as a
// task hands it to Task::probe(). Views: valid only during the sink call.
struct ProbeSample {
  kernel::Time time{0};
  std::string_view node;
  std::string_view task;
  std::string_view channel;
  std::span<const float> values;
};
// Receives every probe sample of a node. Under the thread executor it is called from the probing
// tasks' threads, possibly at once: it must be thread-safe.
using ProbeSink = std::function<void(const ProbeSample&)>;

struct NodeConfig {
  std::string name = "node";
  std::uint64_t seed = 0;
  std::size_t log_capacity = 1024;
  // Where create-by-type-name looks; may be null (then only tasks made in code).
  const TaskTypeRegistry* types = nullptr;
};

class Node {
 public:
  // `executor` must outlive the node.
  Node(kernel::Executor& executor, NodeConfig config);
  // Deletes every task and waits until each has stopped.
  ~Node();
  Node(const Node&) = delete;
  Node& operator=(const Node&) = delete;

  const std::string& name() const { return config_.name; }
  std::uint64_t seed() const { return config_.seed; }
  kernel::Time now() const { return clock_.read(); }
  const kernel::Clock& clock() const { return clock_; }
  SysLog& log() { return log_; }
  const TaskTypeRegistry* types() const { return config_.types; }
  // A fresh stream for `purpose`, the same for the same node seed and purpose.
  kernel::RandomStream random_stream(std::string_view purpose) const;

  // --- tasks -------------------------------------------------------------------------------------
  kernel::Result<TaskId> create(std::string name, std::unique_ptr<Task> task, TaskOptions options = {});
  // Creates a task of a registered type; `params` overrides the type's defaults.
  kernel::Result<TaskId> create(std::string_view type, std::string name, std::span<const ParamAssignment> params,
                                std::optional<TaskOptions> options = std::nullopt);
  kernel::Status start(TaskId id);
  kernel::Status suspend(TaskId id);
  kernel::Status resume(TaskId id);
  // Unhooks the task from everything, then stops it (its on_stop runs on its own context) and frees
  // it. Messages still in its queue are counted as discarded. Safe from the task's own handler.
  kernel::Status remove(TaskId id);
  kernel::Status set_priority(TaskId id, int priority);
  kernel::Status set_period(TaskId id, kernel::Duration period);
  // Checks `value` against the task type's schema now; the task applies it on its own context.
  kernel::Status set_parameter(TaskId id, std::string_view param, std::string_view value);
  // Current parameter values of a task made from a registered type.
  kernel::Result<ParamSet> parameters(TaskId id) const;

  std::optional<TaskId> find(std::string_view task_name) const;
  std::optional<TaskInfo> info(TaskId id) const;
  // The port layouts every hook of the task is checked against (TaskOptions::ports).
  std::optional<PortDeclaration> ports(TaskId id) const;
  std::vector<TaskInfo> tasks() const;
  std::size_t task_count() const;
  // Deletes every task and waits until each has stopped: the node is empty but still usable.
  void clear();
  // Waits until every deleted task has stopped and been freed (under the thread executor a
  // deletion completes on the task's own thread, after remove() returned).
  void wait_released();

  // --- hooks -------------------------------------------------------------------------------------
  // From now on, every send of `sender` also reaches `receiver`'s queue.
  kernel::Result<HookId> hook(TaskId sender, TaskId receiver, HookOptions options = {});
  // From now on, every send of `sender` that the hook lets through is handed to `sink`, on the
  // sender's context (see HookSink). Refuses a suppression window (no receiver queue to guard)
  // and the same sink hooked twice on one port.
  kernel::Result<HookId> hook(TaskId sender, std::shared_ptr<HookSink> sink, HookOptions options = {});
  kernel::Status unhook(HookId id);
  kernel::Status set_hook_enabled(HookId id, bool enabled);
  // Every live hook, with its accounting (see hook.hpp).
  std::vector<HookInfo> hooks() const;
  // The accounting of every hook this node ever had, removed ones included, summed.
  HookTraffic hook_traffic() const;
  // Blocks delivery into `receiver` through hooks of priority < `level` for [now, now + window).
  kernel::Status suppress(TaskId receiver, int level, kernel::Duration window);
  // Blocks `sender`'s output to `receiver` (to every receiver when `receiver` is invalid) for
  // [now, now + window).
  kernel::Status inhibit(TaskId sender, TaskId receiver, kernel::Duration window);

  // Puts a message straight into a task's queue, as from outside any task (source invalid).
  // Fails when the queue refused it (full, under kRefuse) or a suppression window dropped it;
  // either way the message is counted like any other.
  kernel::Status post(TaskId receiver, const Message& message, QueuePolicy policy = QueuePolicy::kRefuse);

  // Sends as task `sender` sends from its handler, from outside its context: how a source outside
  // the node (a network reader) feeds the node's hooks at once, with a task standing for it,
  // rather than through a task of its own that would forward each message on its thread. Every
  // hook of `sender` applies and counts it as one of its sends (hook.hpp): port filter,
  // inhibition, and the receivers' priorities, queue policies and suppression windows. Starts a
  // chain of its own (no hops). May run beside the task's own handlers and other send_as calls.
  // Under the virtual-time executor, on the executor's context only (from a thread: inject()).
  kernel::Status send_as(TaskId sender, Port port, const Payload& payload);

  // Wakes a task without a message, the way an RTOS's direct-to-task notification does: its
  // on_notify() runs once on its own context, before the messages queued with it, however many
  // notifications came first. The cheap way for a device to say that its data is ready (a swarm's
  // sensors say it thousands of times a step): no message is built, queued or counted.
  kernel::Status notify(TaskId receiver);

  // Runs `fn` on the executor's context (see kernel::Executor::inject). The one Node call that
  // a thread outside the executor (a device reader) may make under every executor. `fn` must
  // not assume the node or any task still exists when it runs: pass handles, not pointers.
  void inject(std::function<void()> fn) { executor_.inject(std::move(fn)); }
  // See kernel::Executor::on_own_context: true when node calls may be made here directly.
  bool on_own_context() const { return executor_.on_own_context(); }
  // The executor the node runs on.
  const kernel::Executor& executor() const { return executor_; }

  // --- accounting --------------------------------------------------------------------------------
  // Traffic into every task this node ever had, deleted ones included.
  TrafficCounters traffic() const;
  // Messages now waiting in queues.
  std::uint64_t queued() const;
  // When on, every delivery is folded into a 64-bit hash (time, receiver, source, port, payload
  // bits): equal hashes mean equal message traces.
  void set_tracing(bool on);
  std::uint64_t trace_hash() const;

  // --- cycles (see kMaxHops in message.hpp) ------------------------------------------------------
  // The first cycle of answers the node cut, as a sentence naming its tasks ("message cycle
  // a -> b -> a: ..."); empty when there was none. A run driver (symb run) stops on it and reports
  // it as the run's error.
  std::string cycle_error() const;
  // The longest chain of answers any task of this node handled (in hops, kMaxHops at most).
  std::uint32_t longest_chain() const;
  // How deep messages to tasks that take them at once (Task::take_messages_at_once) may nest,
  // one handler sending to the next inside its own send: past this the message is queued, so
  // the stack stays bounded whatever the task graph.
  static constexpr int kMaxImmediateDepth = 8;

  // --- probes: tasks' internal state for people and plots ----------------------------------------
  // Installs (or, with an empty function, removes) the sink of Task::probe(). Without a sink a
  // probe costs one atomic load, so controllers probe unconditionally or check Task::probing().
  void set_probe_sink(ProbeSink sink);
  bool probing() const { return probing_.load(std::memory_order_acquire); }

 private:
  friend struct detail::TaskRecord;
  friend class Task;

  detail::TaskRecord* lookup_locked(TaskId id) const;
  kernel::Status no_task(TaskId id) const;
  kernel::Status start_locked(detail::TaskRecord& r);
  void release(detail::TaskRecord& r);
  void send_from(detail::TaskRecord& from, const Message& m);
  // The body of a send, under `from`'s out_mu held by `out`; releases it before handing the
  // message to the sinks due. Inline, defined [[gnu::always_inline]] in node.cpp (its only user),
  // with TaskRecord::offer: as three calls, a robot's three hops a step cost 131 instructions more
  // (callgrind, the 1-robot maze).
  inline void send_locked(detail::TaskRecord& from, const Message& m, std::unique_lock<kernel::OptionalMutex>& out);
  void cut_cycle(detail::TaskRecord& from);
  // Under `s`'s out_mu: the accounting of hook `h` of sender `s` (takes the receiver's in_mu).
  static HookTraffic accounting(const detail::TaskRecord& s, const detail::Hook& h);
  // Under mu_ and `s`'s out_mu: `h` goes; its receiver keeps its counts until its messages are
  // handled (a sink's counts retire at once).
  void end_hook(detail::TaskRecord& s, const detail::Hook& h);
  void trace(const detail::TaskRecord& receiver, const Message& m);
  void probe(const detail::TaskRecord& from, std::string_view channel, std::span<const float> values);

  kernel::Executor& executor_;
  const kernel::Clock& clock_;  // the executor's, looked up once: now() is called per message
  NodeConfig config_;
  SysLog log_;
  mutable std::mutex mu_;  // structure: the task table, hook lists' membership, states
  std::condition_variable released_cv_;
  std::vector<detail::TaskSlot> slots_;
  std::vector<std::uint32_t> free_slots_;
  std::size_t live_records_ = 0;
  std::uint32_t hook_serial_ = 0;
  TrafficCounters retired_;    // traffic of deleted tasks
  HookTraffic retired_hooks_;  // hooks into deleted tasks
  std::uint16_t retired_longest_chain_ = 0;
  std::string cycle_error_;
  std::atomic<bool> tracing_{false};
  // Handlers of tasks that take messages at once now running inside a send (kMaxImmediateDepth);
  // only under a non-concurrent executor, on its one context.
  int immediate_depth_ = 0;
  mutable kernel::OptionalMutex trace_mu_;
  std::uint64_t trace_hash_ = 0xcbf29ce484222325ULL;
  std::atomic<bool> probing_{false};
  mutable std::mutex probe_mu_;
  std::shared_ptr<const ProbeSink> probe_sink_;
};

}  // namespace symb::os
