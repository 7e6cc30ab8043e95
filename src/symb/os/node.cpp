#include "symb/os/node.hpp"

#include <algorithm>
#include <cstring>
#include <exception>
#include <new>

#include "symb/kernel/counter.hpp"
#include "symb/kernel/prefetch.hpp"
#include "symb/os/task_record.hpp"

namespace symb::os {

using kernel::Error;
using kernel::Result;
using kernel::Status;

namespace {

std::uint64_t fnv1a(std::string_view s) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (char c : s) h = (h ^ static_cast<unsigned char>(c)) * 0x100000001b3ULL;
  return h;
}

std::string id_text(TaskId id) { return "#" + std::to_string(id.index) + "." + std::to_string(id.generation); }

// A task that can run again (started, resumed) is woken for the messages queued (and the
// notification made) meanwhile, unless a wake-up is pending already. Wakes outside the inbox lock.
void wake_if_queued(detail::TaskRecord& r) {
  kernel::ActivitySlot* wake = nullptr;
  {
    std::lock_guard in(r.in_mu);
    if ((!r.queue.empty() || r.notified) && !r.wake_pending) {
      r.wake_pending = true;
      wake = r.slot;
    }
  }
  if (wake != nullptr) wake->wake();
}

}  // namespace

const char* to_string(TaskState s) {
  switch (s) {
    case TaskState::kCreated: return "created";
    case TaskState::kRunning: return "running";
    case TaskState::kSuspended: return "suspended";
    case TaskState::kFaulted: return "faulted";
    case TaskState::kDeleted: return "deleted";
  }
  return "?";
}

const char* to_string(QueuePolicy p) { return p == QueuePolicy::kKeepNewest ? "keep-newest" : "refuse"; }

TrafficCounters& TrafficCounters::operator+=(const TrafficCounters& o) {
  attempted += o.attempted;
  delivered += o.delivered;
  overwritten += o.overwritten;
  refused += o.refused;
  suppressed += o.suppressed;
  inhibited += o.inhibited;
  discarded += o.discarded;
  return *this;
}

// --- TaskRecord ------------------------------------------------------------------------------------

namespace detail {

TaskRecord::TaskRecord(Node& n, TaskId i, std::string nm, std::unique_ptr<Task> t, const TaskOptions& o,
                       bool concurrent)
    : node(n),
      task(std::move(t)),
      id(i),
      immediate(!concurrent && task->immediate_),
      immediate_notify(!concurrent && task->immediate_notify_),
      in_mu(concurrent),
      queue(o.queue_capacity),
      out_mu(concurrent),
      priority(o.priority),
      period_ns(o.period.count()),
      ports(o.ports ? std::make_unique<const PortDeclaration>(*o.ports) : nullptr),
      name(std::move(nm)),
      random(n.seed(), fnv1a(name)) {
  task->record_ = this;
  task->clock_ = &n.clock();
}

void TaskRecord::on_activity_attached(kernel::ActivitySlot& s) {
  std::lock_guard lock(in_mu);
  slot = &s;
}

void TaskRecord::prefetch(int level) const {
  switch (level) {
    case 0: kernel::prefetch_bytes(this, hot_bytes()); break;
    case 1:
      // What a handler reads first beyond the record: the task object, the queue's head (the
      // message to handle, or where the next one lands; a task is typically handed one or two a
      // step, so two slots), the hooks it sends on, its input side (counters and windows).
      if (task) kernel::prefetch_bytes(task.get(), 2 * kernel::kCacheLine);
      kernel::prefetch_bytes(&queue.at(0), sizeof(Message));
      if (queue.capacity() > 1) kernel::prefetch_bytes(&queue.at(1), sizeof(Message));
      if (!hooks.empty()) kernel::prefetch_line(hooks.data());
      if (inputs) kernel::prefetch_bytes(inputs.get(), sizeof(InputHooks));
      break;
    default:
      if (task) task->prefetch(level - 2);
      break;
  }
}

void TaskRecord::notify(bool may_run_here) {
  // The same conditions as take_now's (can_take_now), and the executor's word that this is the
  // inside of another activity's handler on its own context, so that a task the handler deletes
  // is freed only once it is done.
  if (may_run_here && immediate_notify && !in_handler && !wake_pending && !notified && queue.empty() &&
      !params_pending.load(std::memory_order_relaxed) && node.immediate_depth_ < Node::kMaxImmediateDepth &&
      state.load(std::memory_order_relaxed) == TaskState::kRunning && slot != nullptr && slot->can_run_inline()) {
    take_notification_now();
    return;
  }
  kernel::ActivitySlot* wake = nullptr;
  {
    std::lock_guard in(in_mu);
    notified = true;
    if (!wake_pending && slot != nullptr) {
      wake_pending = true;
      wake = slot;
    }
  }
  if (wake != nullptr) wake->wake();
}

void TaskRecord::fault(const char* where, const char* what) {
  TaskState s = state.load();
  while ((s == TaskState::kRunning || s == TaskState::kSuspended) &&
         !state.compare_exchange_weak(s, TaskState::kFaulted)) {
  }
  node.log().error(name, std::string("faulted in ") + where + ": " + what);
  slot->suspend();
}

#define SYMB_GUARDED(where, call)                              \
  try {                                                        \
    call;                                                      \
  } catch (const std::exception& e) {                          \
    fault(where, e.what());                                    \
  } catch (...) {                                              \
    fault(where, "an exception that is not a std::exception"); \
  }

// Marks a handler of the record as running, for take_now.
struct InHandler {
  bool& flag;
  explicit InHandler(bool& f) : flag(f) { flag = true; }
  ~InHandler() { flag = false; }
  InHandler(const InHandler&) = delete;
  InHandler& operator=(const InHandler&) = delete;
};

void TaskRecord::on_activity_start() {
  if (state.load() != TaskState::kRunning) return;
  const InHandler busy(in_handler);
  SYMB_GUARDED("on_start", task->on_start())
}

void TaskRecord::apply_parameters_now() {
  std::vector<std::pair<std::string, ParamValue>> pending;
  {
    std::lock_guard lock(in_mu);
    params_pending.store(false, std::memory_order_relaxed);
    if (params->pending.empty()) return;
    pending.swap(params->pending);
  }
  for (auto& [n, v] : pending) {
    Status st;
    SYMB_GUARDED("on_parameter", st = task->on_parameter(n, v))
    if (!st) {
      node.log().warn(name, "parameter '" + n + "' not changed: " + st.error());
      continue;
    }
    std::lock_guard lock(in_mu);
    params->values.set(n, std::move(v));
  }
}

void TaskRecord::on_activity_input() {
  apply_pending_parameters();
  // The message being handled, moved out of the queue (outside in_mu, so senders can queue more
  // meanwhile). Its payload's numbers are left unset: only the ones a message carries are copied in.
  Message handling{.source = {}, .port = 0, .hops = 0, .edge = 0, .time = {}, .payload = Payload(Payload::kUnset)};
  const InHandler busy(in_handler);
  for (;;) {
    bool notification = false;
    {
      std::lock_guard lock(in_mu);
      // A task suspended, faulted or deleted mid-batch leaves the rest queued (and a notification
      // due); whoever resumes it wakes it again.
      if ((queue.empty() && !notified) || state.load(std::memory_order_relaxed) != TaskState::kRunning) {
        wake_pending = false;
        next_hops = 0;
        return;
      }
      // A notification comes before the messages queued with it: it says that the device's data
      // is ready, which is what a message it is about to handle may be asking for.
      if (notified) {
        notified = false;
        notification = true;
      } else {
        handling = std::move(queue.front());
        queue.pop();
        if (InHook* e = in_hook(handling.edge)) {
          ++e->traffic.delivered;
          if (!e->hooked) retire_in_hook_if_done(handling.edge);
        }
      }
    }
    if (notification) {
      // What it sends starts a chain of its own, as from a tick.
      next_hops = 0;
      SYMB_GUARDED("on_notify", task->on_notify())
      continue;
    }
    handle_message(handling);
    handling.payload.blob.reset();  // a large payload is freed when its last handler is done
  }
}

[[gnu::always_inline]] inline void TaskRecord::handle_message(const Message& m) {
  kernel::bump(delivered);
  next_hops = static_cast<std::uint16_t>(m.hops + 1);
  if (m.hops > longest_chain.load(std::memory_order_relaxed)) longest_chain.store(m.hops, std::memory_order_relaxed);
  if (m.hops > kMaxHops / 2) [[unlikely]]
    deep_source.store((std::uint64_t{m.source.index} << 32) | m.source.generation, std::memory_order_relaxed);
  if (node.tracing_.load(std::memory_order_relaxed)) node.trace(*this, m);
  SYMB_GUARDED("on_message", task->on_message(m))
}

bool TaskRecord::can_take_now() const {
  // Asked only from inside a handler of the sender, under a non-concurrent executor (in_mu is
  // off): so on the executor's one context, inside its run, where a task deleted by a handler is
  // freed only once that handler is done. The receiver is idle unless it is inside a handler
  // itself, on this very stack further up. Parameters waiting are applied by an activation, as
  // the message then is.
  return !in_handler && !taking_now && !wake_pending && !notified && queue.empty() &&
         !params_pending.load(std::memory_order_relaxed) && node.immediate_depth_ < Node::kMaxImmediateDepth &&
         state.load(std::memory_order_relaxed) == TaskState::kRunning;
}

void TaskRecord::take_now(const Message& m, std::uint32_t edge, QueuePolicy policy) {
  taking_now = false;
  // A receiver handled earlier in the same send may have suspended or deleted this one: then the
  // message joins its queue, as a message for a task that is not running does. What it may have
  // sent this one meanwhile is queued (taking_now) and came later than this message: it is
  // handled after it, by the activation its queueing scheduled.
  if (in_handler || params_pending.load(std::memory_order_relaxed) ||
      node.immediate_depth_ >= Node::kMaxImmediateDepth ||
      state.load(std::memory_order_relaxed) != TaskState::kRunning) {
    if (kernel::ActivitySlot* wake = enqueue(m, edge, policy, in_hook(edge))) wake->wake();
    return;
  }
  if (InHook* e = in_hook(edge)) {
    ++e->traffic.delivered;
    if (!e->hooked) retire_in_hook_if_done(edge);
  }
  const InHandler busy(in_handler);
  ++node.immediate_depth_;
  handle_message(m);
  next_hops = 0;
  --node.immediate_depth_;
}

void TaskRecord::take_notification_now() {
  const InHandler busy(in_handler);
  ++node.immediate_depth_;
  // What it sends starts a chain of its own, as from an activation's notification.
  next_hops = 0;
  SYMB_GUARDED("on_notify", task->on_notify())
  next_hops = 0;
  --node.immediate_depth_;
}

void TaskRecord::on_activity_tick() {
  apply_pending_parameters();
  if (state.load(std::memory_order_relaxed) != TaskState::kRunning) return;
  const InHandler busy(in_handler);
  SYMB_GUARDED("on_tick", task->on_tick())
}

void TaskRecord::on_activity_stop() {
  const InHandler busy(in_handler);
  try {
    task->on_stop();
  } catch (const std::exception& e) {
    node.log().error(name, std::string("exception in on_stop: ") + e.what());
  } catch (...) {
    node.log().error(name, "exception in on_stop");
  }
}

#undef SYMB_GUARDED

void TaskRecord::on_activity_released() { node.release(*this); }

[[gnu::always_inline]] kernel::ActivitySlot* TaskRecord::offer(const Message& m, std::uint32_t edge, int hook_priority,
                                                               QueuePolicy policy, kernel::Duration suppress_window,
                                                               bool* accepted) {
  std::lock_guard lock(in_mu);
  if (accepted != nullptr) *accepted = false;
  InHook* e = in_hook(edge);
  if (!admit(m, e, hook_priority, suppress_window)) return nullptr;
  return enqueue(m, edge, policy, e, accepted);
}

[[gnu::always_inline]] inline kernel::ActivitySlot* TaskRecord::enqueue(const Message& m, std::uint32_t edge,
                                                                        QueuePolicy policy, InHook* e, bool* accepted) {
  if (queue.full()) {
    if (policy == QueuePolicy::kRefuse) {
      ++traffic.refused;
      if (e != nullptr) ++e->traffic.refused;
      return nullptr;
    }
    ++traffic.overwritten;
    // The oldest message goes: counted against the hook it came through.
    const std::uint32_t old_edge = queue.front().edge;
    queue.pop();
    if (InHook* o = in_hook(old_edge)) {
      ++o->traffic.overwritten;
      if (!o->hooked) retire_in_hook_if_done(old_edge);
    }
  }
  queue.push(m);
  queue.back().edge = edge;
  if (accepted != nullptr) *accepted = true;
  if (wake_pending || slot == nullptr) return nullptr;
  wake_pending = true;
  return slot;
}

[[gnu::always_inline]] inline bool TaskRecord::admit(const Message& m, InHook* e, int hook_priority,
                                                     kernel::Duration suppress_window) {
  ++traffic.attempted;
  if (e != nullptr) ++e->traffic.attempted;
  if (inputs) {
    for (const auto& w : inputs->suppression) {
      if (hook_priority < w.level && m.time < w.until) {
        ++traffic.suppressed;
        if (e != nullptr) ++e->traffic.suppressed;
        return false;
      }
    }
  }
  if (suppress_window.count() > 0) {
    // Keep the window of this level, or the one that ends first, up to date.
    const kernel::Time until = m.time + suppress_window;
    SuppressionWindow& target = input_hooks().window_for(hook_priority, m.time);
    if (target.level != hook_priority || target.until < until) target = {hook_priority, until};
  }
  return true;
}

SuppressionWindow& InputHooks::window_for(int level, kernel::Time now) {
  SuppressionWindow* target = &suppression[0];
  for (auto& w : suppression) {
    if (w.level == level || w.until <= now) return w;
    if (w.until < target->until) target = &w;
  }
  return *target;
}

std::uint32_t TaskRecord::add_in_hook(std::uint32_t serial) {
  InputHooks& in = input_hooks();
  std::uint32_t slot_index;
  if (!in.free_slots.empty()) {
    slot_index = in.free_slots.back();
    in.free_slots.pop_back();
  } else {
    slot_index = in.add_slot();
  }
  InHook& e = in.at(slot_index);
  e = InHook{};
  e.serial = serial;
  e.hooked = true;
  return slot_index + 1;
}

void TaskRecord::end_in_hook(std::uint32_t edge, std::uint64_t sent_while_hooked, std::uint64_t skipped) {
  InHook& e = inputs->at(edge - 1);
  e.hooked = false;
  e.sent = sent_while_hooked;
  e.skipped = skipped;
  retire_in_hook_if_done(edge);
}

void TaskRecord::retire_in_hook_if_done(std::uint32_t edge) {
  InHook& e = inputs->at(edge - 1);
  if (e.hooked || e.serial == 0 || e.in_flight() != 0) return;
  inputs->retired += HookTraffic{e.sent, e.skipped, e.traffic, 0};
  e.serial = 0;
  inputs->free_slots.push_back(edge - 1);
}

}  // namespace detail

// --- Node ------------------------------------------------------------------------------------------

using detail::TaskRecord;

Node::Node(kernel::Executor& executor, NodeConfig config)
    : executor_(executor),
      clock_(executor.clock()),
      config_(std::move(config)),
      log_(executor.clock(), config_.log_capacity),
      trace_mu_(executor.concurrent()) {}

Node::~Node() { clear(); }

void Node::clear() {
  std::vector<TaskId> ids;
  {
    std::lock_guard lock(mu_);
    for (const auto& s : slots_)
      if (s.record && s.record->state.load() != TaskState::kDeleted) ids.push_back(s.record->id);
  }
  for (TaskId id : ids) (void)remove(id);
  std::unique_lock lock(mu_);
  released_cv_.wait(lock, [&] { return live_records_ == 0; });
}

void Node::wait_released() {
  std::unique_lock lock(mu_);
  released_cv_.wait(lock, [&] {
    return std::none_of(slots_.begin(), slots_.end(), [](const detail::TaskSlot& s) {
      return s.record && s.record->state.load() == TaskState::kDeleted;
    });
  });
}

kernel::RandomStream Node::random_stream(std::string_view purpose) const {
  return kernel::RandomStream(config_.seed, fnv1a(purpose) ^ 0x5bd1e995ULL);
}

TaskRecord* Node::lookup_locked(TaskId id) const {
  if (id.index >= slots_.size()) return nullptr;
  const auto& s = slots_[id.index];
  if (!s.record || s.generation != id.generation || s.record->state.load() == TaskState::kDeleted) return nullptr;
  return s.record.get();
}

Status Node::no_task(TaskId id) const {
  return Error{"node '" + config_.name + "' has no task " + (id.valid() ? id_text(id) : std::string("(invalid id)"))};
}

Result<TaskId> Node::create(std::string name, std::unique_ptr<Task> task, TaskOptions options) {
  if (!is_valid_name(name))
    return Error{"invalid task name '" + name.substr(0, 63) +
                 "': use 1 to 63 letters, digits, '_', '.' or '-', starting with a letter or '_'"};
  if (!task) return Error{"task '" + name + "': no task object"};
  if (options.queue_capacity == 0 || options.queue_capacity > (1u << 20))
    return Error{"task '" + name + "': queue capacity must be between 1 and 1048576"};
  if (options.period.count() < 0) return Error{"task '" + name + "': negative period"};
  TaskId id;
  {
    std::lock_guard lock(mu_);
    for (const auto& s : slots_)
      if (s.record && s.record->state.load() != TaskState::kDeleted && s.record->name == name)
        return Error{"node '" + config_.name + "' already has a task named '" + name + "'"};
    if (!free_slots_.empty()) {
      id.index = free_slots_.back();
      free_slots_.pop_back();
    } else {
      id.index = static_cast<std::uint32_t>(slots_.size());
      slots_.emplace_back();
    }
    auto& slot = slots_[id.index];
    id.generation = slot.generation;
    slot.record =
        std::make_unique<TaskRecord>(*this, id, std::move(name), std::move(task), options, executor_.concurrent());
    ++live_records_;
  }
  if (options.autostart)
    if (auto st = start(id); !st) {
      (void)remove(id);
      return Error{st.error()};
    }
  return id;
}

Result<TaskId> Node::create(std::string_view type_name, std::string name, std::span<const ParamAssignment> params,
                            std::optional<TaskOptions> options) {
  if (config_.types == nullptr) return Error{"node '" + config_.name + "' has no task type registry"};
  const TaskType* type = config_.types->find(type_name);
  if (type == nullptr) return Error{config_.types->unknown_type_error(type_name)};
  auto values = config_.types->resolve(*type, params);
  if (!values) return Error{values.error()};
  std::unique_ptr<Task> task;
  // Factories report errors as values; a constructor that throws anyway (std::bad_alloc for a huge
  // size) must not take the node down either.
  const std::string failed = "task type '" + type->name + "' could not make a task: ";
  try {
    auto made = type->make(*values);
    if (!made) return Error{failed + made.error()};
    task = std::move(made).value();
  } catch (const std::bad_alloc&) {
    return Error{failed + "out of memory (a size too large?)"};
  } catch (const std::exception& e) {
    return Error{failed + e.what()};
  } catch (...) {
    return Error{failed + "an exception that is not a std::exception"};
  }
  if (!task) return Error{"task type '" + type->name + "' made no task"};
  auto state = std::make_unique<detail::ParamState>();
  state->type = type;
  state->values = std::move(values).value();
  const TaskOptions o = options.value_or(type->defaults);
  // Parameters must be in place before the task can start, so create it unstarted first.
  TaskOptions unstarted = o;
  unstarted.autostart = false;
  const PortEnd declared{name, type->name, type->inputs, type->outputs};
  if (unstarted.ports) {
    if (auto st = check_declaration_fits(*unstarted.ports, declared); !st)
      return Error{"task '" + name + "' (" + type->name + "): " + st.error()};
  } else {
    unstarted.ports = PortDeclaration{type->inputs, type->outputs};
  }
  auto id = create(std::move(name), std::move(task), unstarted);
  if (!id) return id;
  {
    std::lock_guard lock(mu_);
    TaskRecord* r = lookup_locked(*id);
    std::lock_guard in(r->in_mu);
    r->params = std::move(state);
  }
  if (o.autostart)
    if (auto st = start(*id); !st) return Error{st.error()};
  return id;
}

Status Node::start_locked(TaskRecord& r) {
  kernel::ActivityOptions ao;
  ao.priority = r.priority.load();
  ao.period = kernel::Duration{r.period_ns.load()};
  ao.name = r.name;
  r.state.store(TaskState::kRunning);
  try {
    executor_.attach(r, ao);
  } catch (const std::exception& e) {
    // Out of threads, typically: the task stays `created`, nothing half-started is left behind.
    r.state.store(TaskState::kCreated);
    return Error{"task '" + r.name + "' could not start: " + e.what()};
  }
  return {};
}

Status Node::start(TaskId id) {
  std::lock_guard lock(mu_);
  TaskRecord* r = lookup_locked(id);
  if (r == nullptr) return no_task(id);
  if (r->state.load() != TaskState::kCreated)
    return Error{"task '" + r->name + "' is " + to_string(r->state.load()) + ", not created"};
  if (auto st = start_locked(*r); !st) return st;
  // Messages may have been queued before it started.
  wake_if_queued(*r);
  return {};
}

Status Node::suspend(TaskId id) {
  std::lock_guard lock(mu_);
  TaskRecord* r = lookup_locked(id);
  if (r == nullptr) return no_task(id);
  TaskState expected = TaskState::kRunning;
  if (!r->state.compare_exchange_strong(expected, TaskState::kSuspended))
    return Error{"task '" + r->name + "' is " + to_string(expected) + ", not running"};
  r->slot->suspend();
  return {};
}

Status Node::resume(TaskId id) {
  std::lock_guard lock(mu_);
  TaskRecord* r = lookup_locked(id);
  if (r == nullptr) return no_task(id);
  TaskState expected = TaskState::kSuspended;
  if (!r->state.compare_exchange_strong(expected, TaskState::kRunning))
    return Error{"task '" + r->name + "' is " + to_string(expected) + ", not suspended"};
  r->slot->resume();
  wake_if_queued(*r);
  return {};
}

Status Node::remove(TaskId id) {
  kernel::ActivitySlot* slot = nullptr;
  TaskRecord* never_started = nullptr;
  {
    std::lock_guard lock(mu_);
    TaskRecord* r = lookup_locked(id);
    if (r == nullptr) return no_task(id);
    // Unhook it from every sender first: after this, no send can reach it.
    for (auto& s : slots_) {
      if (!s.record) continue;
      std::lock_guard out(s.record->out_mu);
      std::erase_if(s.record->hooks, [&](const detail::Hook& h) {
        if (h.task() != r) return false;
        end_hook(*s.record, h);
        return true;
      });
    }
    {
      std::lock_guard out(r->out_mu);
      for (const auto& h : r->hooks) end_hook(*r, h);
      r->hooks.clear();
    }
    const TaskState before = r->state.exchange(TaskState::kDeleted);
    {
      std::lock_guard in(r->in_mu);
      slot = r->slot;
    }
    if (before == TaskState::kCreated) never_started = r;
  }
  // Outside the node lock: stopping runs the task's on_stop, which may call back into the node.
  if (never_started != nullptr)
    release(*never_started);
  else if (slot != nullptr)
    slot->detach();
  return {};
}

void Node::release(TaskRecord& r) {
  std::unique_ptr<TaskRecord> dying;
  {
    std::lock_guard lock(mu_);
    {
      std::lock_guard in(r.in_mu);
      r.traffic.discarded += r.queue.size();
      while (!r.queue.empty()) {
        if (detail::InHook* e = r.in_hook(r.queue.front().edge)) ++e->traffic.discarded;
        r.queue.pop();
      }
      r.queue.clear();
      TrafficCounters t = r.traffic;
      t.delivered = r.delivered.load();
      retired_ += t;
      // Every hook into it ended in remove(): what is left are their final counts.
      if (r.inputs) {
        retired_hooks_ += r.inputs->retired;
        for (std::uint32_t i = 0; i < r.inputs->slot_count; ++i)
          if (const auto& e = r.inputs->at(i); e.serial != 0)
            retired_hooks_ += HookTraffic{e.sent, e.skipped, e.traffic, 0};
      }
      retired_longest_chain_ = std::max(retired_longest_chain_, r.longest_chain.load(std::memory_order_relaxed));
    }
    auto& s = slots_[r.id.index];
    dying = std::move(s.record);
    ++s.generation;
    free_slots_.push_back(r.id.index);
  }
  // The task object is destroyed outside the lock (its destructor may do anything) but before
  // the count drops, so the node's destructor cannot finish while a task is still being torn down.
  dying.reset();
  std::lock_guard lock(mu_);
  --live_records_;
  // Notified under the lock: once the waiter sees the count it may destroy the condition variable.
  released_cv_.notify_all();
}

Status Node::set_priority(TaskId id, int priority) {
  std::lock_guard lock(mu_);
  TaskRecord* r = lookup_locked(id);
  if (r == nullptr) return no_task(id);
  r->priority.store(priority);
  std::lock_guard in(r->in_mu);
  if (r->slot != nullptr) r->slot->set_priority(priority);
  return {};
}

Status Node::set_period(TaskId id, kernel::Duration period) {
  if (period.count() < 0) return Error{"negative period"};
  std::lock_guard lock(mu_);
  TaskRecord* r = lookup_locked(id);
  if (r == nullptr) return no_task(id);
  r->period_ns.store(period.count());
  std::lock_guard in(r->in_mu);
  if (r->slot != nullptr) r->slot->set_period(period);
  return {};
}

Status Node::set_parameter(TaskId id, std::string_view param, std::string_view value) {
  kernel::ActivitySlot* wake = nullptr;
  {
    std::lock_guard lock(mu_);
    TaskRecord* r = lookup_locked(id);
    if (r == nullptr) return no_task(id);
    std::lock_guard in(r->in_mu);
    if (!r->params) return Error{"task '" + r->name + "' was not made from a registered type: it has no parameters"};
    const TaskType& type = *r->params->type;
    const ParamSpec* spec = type.param(param);
    if (spec == nullptr) {
      std::vector<std::string_view> names;
      for (const auto& p : type.params) names.push_back(p.name);
      std::string msg = "task type '" + type.name + "' has no parameter '" + std::string(param.substr(0, 63)) + "'";
      if (auto hint = closest_name(param, names); !hint.empty()) msg += " (did you mean '" + hint + "'?)";
      return Error{msg};
    }
    auto v = parse_param_value(*spec, value);
    if (!v) return Error{v.error()};
    r->params->pending.emplace_back(spec->name, std::move(v).value());
    r->params_pending.store(true, std::memory_order_release);
    // Wake the task so that it applies the change on its own context soon.
    if (!r->wake_pending && r->slot != nullptr) {
      r->wake_pending = true;
      wake = r->slot;
    }
    if (wake != nullptr) wake->wake();
  }
  return {};
}

Result<ParamSet> Node::parameters(TaskId id) const {
  std::lock_guard lock(mu_);
  TaskRecord* r = lookup_locked(id);
  if (r == nullptr) return Error{no_task(id).error()};
  std::lock_guard in(r->in_mu);
  if (!r->params) return ParamSet{};
  return r->params->values;
}

std::optional<TaskId> Node::find(std::string_view task_name) const {
  std::lock_guard lock(mu_);
  for (const auto& s : slots_)
    if (s.record && s.record->state.load() != TaskState::kDeleted && s.record->name == task_name) return s.record->id;
  return std::nullopt;
}

namespace {

TaskInfo describe(TaskRecord& r) {
  TaskInfo i;
  i.id = r.id;
  i.name = r.name;
  i.state = r.state.load();
  i.priority = r.priority.load();
  i.period = kernel::Duration{r.period_ns.load()};
  i.sent = r.sent.load(std::memory_order_relaxed);
  std::lock_guard in(r.in_mu);
  i.type = r.params ? r.params->type->name : "-";
  i.queue_depth = r.queue.size();
  i.queue_capacity = r.queue.capacity();
  i.traffic = r.traffic;
  i.traffic.delivered = r.delivered.load(std::memory_order_relaxed);
  return i;
}

}  // namespace

std::optional<PortDeclaration> Node::ports(TaskId id) const {
  std::lock_guard lock(mu_);
  const TaskRecord* r = lookup_locked(id);
  if (r == nullptr) return std::nullopt;
  return r->ports ? *r->ports : PortDeclaration{};
}

std::optional<TaskInfo> Node::info(TaskId id) const {
  std::lock_guard lock(mu_);
  TaskRecord* r = lookup_locked(id);
  if (r == nullptr) return std::nullopt;
  return describe(*r);
}

std::vector<TaskInfo> Node::tasks() const {
  std::lock_guard lock(mu_);
  std::vector<TaskInfo> out;
  for (const auto& s : slots_)
    if (s.record && s.record->state.load() != TaskState::kDeleted) out.push_back(describe(*s.record));
  return out;
}

std::size_t Node::task_count() const {
  std::lock_guard lock(mu_);
  std::size_t n = 0;
  for (const auto& s : slots_)
    if (s.record && s.record->state.load() != TaskState::kDeleted) ++n;
  return n;
}

namespace {

// The declared ports of a hook's end, for check_layouts.
PortEnd port_end(const TaskRecord& t) {
  const std::string_view type = t.params ? std::string_view(t.params->type->name) : std::string_view("-");
  if (!t.ports) return {t.name, type, {}, {}};
  return {t.name, type, t.ports->inputs, t.ports->outputs};
}

}  // namespace

Result<HookId> Node::hook(TaskId sender, TaskId receiver, HookOptions options) {
  std::lock_guard lock(mu_);
  TaskRecord* s = lookup_locked(sender);
  if (s == nullptr) return Error{no_task(sender).error()};
  TaskRecord* r = lookup_locked(receiver);
  if (r == nullptr) return Error{no_task(receiver).error()};
  // One rule with scenario files: a task's output never feeds its own queue (a cycle of one).
  if (s == r) return Error{"task '" + s->name + "' is hooked to itself"};
  if (options.port > 0xffff) return Error{"hook port must be -1 (any) or 0..65535"};
  if (options.suppress_window.count() < 0) return Error{"negative suppression window"};
  if (auto st = check_layouts(port_end(*s), port_end(*r), options.port); !st) return Error{st.error()};
  detail::Hook h;
  h.priority = options.priority;
  h.port = options.port < 0 ? -1 : options.port;
  h.policy = options.policy;
  h.enabled = options.enabled;
  h.receiver = r;
  h.suppress_window = options.suppress_window;
  {
    std::lock_guard out(s->out_mu);
    for (const detail::Hook& x : s->hooks)
      if (x.task() == r && same_hook_key(x.port, h.port))
        return Error{"task '" + s->name + "' is already hooked to '" + r->name + "'" +
                     (h.port < 0 ? std::string() : " on port " + std::to_string(h.port)) + " (hook " +
                     std::to_string(x.serial) + ")"};
    h.serial = ++hook_serial_;
    h.sent_before = s->sent.load(std::memory_order_relaxed);
    {
      std::lock_guard in(r->in_mu);
      h.edge = r->add_in_hook(h.serial);
    }
    // Higher-priority hooks deliver first; equal priorities keep hook order.
    auto at =
        std::find_if(s->hooks.begin(), s->hooks.end(), [&](const detail::Hook& x) { return x.priority < h.priority; });
    s->hooks.insert(at, h);
  }
  return HookId{sender.index, h.serial};
}

Result<HookId> Node::hook(TaskId sender, std::shared_ptr<HookSink> sink, HookOptions options) {
  std::lock_guard lock(mu_);
  TaskRecord* s = lookup_locked(sender);
  if (s == nullptr) return Error{no_task(sender).error()};
  if (!sink) return Error{"task '" + s->name + "': no sink to hook to"};
  if (options.port > 0xffff) return Error{"hook port must be -1 (any) or 0..65535"};
  if (options.suppress_window.count() != 0)
    return Error{"hook from '" + s->name + "' to sink '" + sink->name() +
                 "': a sink has no queue for a suppression window to guard"};
  detail::Hook h;
  h.priority = options.priority;
  h.port = options.port < 0 ? -1 : options.port;
  h.policy = options.policy;
  h.enabled = options.enabled;
  std::lock_guard out(s->out_mu);
  for (const detail::Hook& x : s->hooks)
    if (x.to_sink && x.sink->sink == sink && same_hook_key(x.port, h.port))
      return Error{"task '" + s->name + "' is already hooked to sink '" + sink->name() + "'" +
                   (h.port < 0 ? std::string() : " on port " + std::to_string(h.port)) + " (hook " +
                   std::to_string(x.serial) + ")"};
  h.serial = ++hook_serial_;
  h.sent_before = s->sent.load(std::memory_order_relaxed);
  h.to_sink = true;
  h.sink = new detail::SinkEnd{std::move(sink), {}, false};  // freed by end_hook
  auto at =
      std::find_if(s->hooks.begin(), s->hooks.end(), [&](const detail::Hook& x) { return x.priority < h.priority; });
  s->hooks.insert(at, h);
  return HookId{sender.index, h.serial};
}

Status Node::unhook(HookId id) {
  std::lock_guard lock(mu_);
  if (id.sender_index < slots_.size() && slots_[id.sender_index].record) {
    TaskRecord& s = *slots_[id.sender_index].record;
    std::lock_guard out(s.out_mu);
    auto it =
        std::find_if(s.hooks.begin(), s.hooks.end(), [&](const detail::Hook& h) { return h.serial == id.serial; });
    if (it != s.hooks.end()) {
      end_hook(s, *it);
      s.hooks.erase(it);
      return {};
    }
  }
  return Error{"node '" + config_.name + "' has no hook " + std::to_string(id.serial)};
}

Status Node::set_hook_enabled(HookId id, bool enabled) {
  std::lock_guard lock(mu_);
  if (id.sender_index < slots_.size() && slots_[id.sender_index].record) {
    TaskRecord& s = *slots_[id.sender_index].record;
    std::lock_guard out(s.out_mu);
    for (auto& h : s.hooks)
      if (h.serial == id.serial) {
        h.enabled = enabled;
        return {};
      }
  }
  return Error{"node '" + config_.name + "' has no hook " + std::to_string(id.serial)};
}

std::vector<HookInfo> Node::hooks() const {
  std::lock_guard lock(mu_);
  std::vector<HookInfo> out;
  for (const auto& s : slots_) {
    if (!s.record || s.record->state.load() == TaskState::kDeleted) continue;
    std::lock_guard o(s.record->out_mu);
    for (const auto& h : s.record->hooks) {
      HookInfo i;
      i.id = HookId{s.record->id.index, h.serial};
      i.sender = s.record->id;
      i.sender_name = s.record->name;
      if (h.to_sink) {
        i.receiver_name = h.sink->sink->name();
        i.sink = h.sink->sink;
      } else {
        i.receiver = h.receiver->id;
        i.receiver_name = h.receiver->name;
      }
      i.options = HookOptions{h.priority, h.policy, h.enabled, h.port, h.suppress_window};
      i.inhibited_until = h.inhibited_until;
      i.accounting = accounting(*s.record, h);
      out.push_back(std::move(i));
    }
  }
  return out;
}

HookTraffic Node::accounting(const TaskRecord& s, const detail::Hook& h) {
  HookTraffic a;
  a.sent = s.sent.load(std::memory_order_relaxed) - h.sent_before;
  a.skipped = h.skipped;
  if (h.to_sink) {
    a.traffic = h.sink->traffic;  // nothing queued: handed over at once
    return a;
  }
  TaskRecord& r = *h.receiver;
  std::lock_guard in(r.in_mu);
  a.traffic = r.inputs->at(h.edge - 1).traffic;
  // Counted, not derived: a message lost between the counters would show here.
  for (std::size_t k = 0; k < r.queue.size(); ++k)
    if (r.queue.at(k).edge == h.edge) ++a.queued;
  return a;
}

void Node::end_hook(TaskRecord& s, const detail::Hook& h) {
  if (h.to_sink) {
    retired_hooks_ +=
        HookTraffic{s.sent.load(std::memory_order_relaxed) - h.sent_before, h.skipped, h.sink->traffic, 0};
    delete h.sink;  // a send under way holds its own reference to the sink
    return;
  }
  std::lock_guard in(h.receiver->in_mu);
  h.receiver->end_in_hook(h.edge, s.sent.load(std::memory_order_relaxed) - h.sent_before, h.skipped);
}

HookTraffic Node::hook_traffic() const {
  std::lock_guard lock(mu_);
  HookTraffic t = retired_hooks_;
  for (const auto& s : slots_) {
    if (!s.record) continue;
    {
      std::lock_guard out(s.record->out_mu);
      for (const auto& h : s.record->hooks) t += accounting(*s.record, h);
    }
    TaskRecord& r = *s.record;
    std::lock_guard in(r.in_mu);
    if (!r.inputs) continue;
    t += r.inputs->retired;
    for (std::uint32_t i = 0; i < r.inputs->slot_count; ++i) {
      const auto& e = r.inputs->at(i);
      if (e.serial == 0 || e.hooked) continue;  // live hooks were counted from their sender
      HookTraffic ended{e.sent, e.skipped, e.traffic, 0};
      const std::uint32_t edge = i + 1;
      for (std::size_t k = 0; k < r.queue.size(); ++k)
        if (r.queue.at(k).edge == edge) ++ended.queued;
      t += ended;
    }
  }
  return t;
}

Status Node::suppress(TaskId receiver, int level, kernel::Duration window) {
  if (window.count() < 0) return Error{"negative suppression window"};
  std::lock_guard lock(mu_);
  TaskRecord* r = lookup_locked(receiver);
  if (r == nullptr) return no_task(receiver);
  const kernel::Time now = this->now();
  std::lock_guard in(r->in_mu);
  r->input_hooks().window_for(level, now) = {level, now + window};
  return {};
}

Status Node::inhibit(TaskId sender, TaskId receiver, kernel::Duration window) {
  if (window.count() < 0) return Error{"negative inhibition window"};
  std::lock_guard lock(mu_);
  TaskRecord* s = lookup_locked(sender);
  if (s == nullptr) return no_task(sender);
  TaskRecord* r = nullptr;
  if (receiver.valid()) {
    r = lookup_locked(receiver);
    if (r == nullptr) return no_task(receiver);
  }
  const kernel::Time until = now() + window;
  std::lock_guard out(s->out_mu);
  bool any = false;
  for (auto& h : s->hooks)
    if (r == nullptr || h.task() == r) {
      h.inhibited_until = until;
      any = true;
    }
  if (!any) return Error{"task '" + s->name + "' has no hook " + (r ? "to '" + r->name + "'" : std::string("at all"))};
  return {};
}

Status Node::post(TaskId receiver, const Message& message, QueuePolicy policy) {
  std::lock_guard lock(mu_);
  TaskRecord* r = lookup_locked(receiver);
  if (r == nullptr) return no_task(receiver);
  Message m = message;
  m.time = now();
  bool accepted = false;
  if (kernel::ActivitySlot* wake = r->offer(m, 0, 0, policy, kernel::Duration{0}, &accepted)) wake->wake();
  if (!accepted) return Error{"task '" + r->name + "' did not take the message (queue full or suppressed)"};
  return {};
}

Status Node::notify(TaskId receiver) {
  std::lock_guard lock(mu_);
  TaskRecord* r = lookup_locked(receiver);
  if (r == nullptr) return no_task(receiver);
  r->notify(false);  // under mu_: never on_notify here
  return {};
}

void Node::send_from(TaskRecord& from, const Message& m) {
  if (m.hops > kMaxHops) [[unlikely]] {
    cut_cycle(from);
    return;
  }
  std::unique_lock out(from.out_mu);
  send_locked(from, m, out);
}

[[gnu::always_inline]] void Node::send_locked(TaskRecord& from, const Message& m,
                                              std::unique_lock<kernel::OptionalMutex>& out) {
  kernel::bump(from.sent);
  bool sinks_due = false;
  // Receivers that take the message at once (Task::take_messages_at_once): admitted and counted
  // here with the others, handed the message once every hook has had it. So no handler runs
  // while this loop walks the hooks (a handler may rewire them), and what a receiver sends from
  // its handler reaches the others behind this message, as it would through their queues. Past
  // kAtOnce of them in one send, the rest are queued.
  constexpr std::size_t kAtOnce = 4;
  struct AtOnce {
    TaskRecord* receiver;
    std::uint32_t edge;
    QueuePolicy policy;
  } at_once[kAtOnce];
  std::size_t n_at_once = 0;
  for (auto& h : from.hooks) {
    if (!h.enabled || (h.port >= 0 && h.port != m.port)) {
      ++h.skipped;
      continue;
    }
    if (h.to_sink) [[unlikely]] {
      detail::SinkEnd& e = *h.sink;
      ++e.traffic.attempted;
      if (m.time < h.inhibited_until) {
        ++e.traffic.inhibited;
        continue;
      }
      ++e.traffic.delivered;
      e.due = sinks_due = true;
      continue;
    }
    if (m.time < h.inhibited_until) {
      std::lock_guard in(h.receiver->in_mu);
      ++h.receiver->traffic.attempted;
      ++h.receiver->traffic.inhibited;
      detail::InHook& e = *h.receiver->in_hook(h.edge);
      ++e.traffic.attempted;
      ++e.traffic.inhibited;
      continue;
    }
    if (h.receiver->immediate && from.in_handler && n_at_once < kAtOnce && h.receiver->can_take_now()) {
      if (h.receiver->admit(m, h.receiver->in_hook(h.edge), h.priority, h.suppress_window)) {
        h.receiver->taking_now = true;
        at_once[n_at_once++] = {h.receiver, h.edge, h.policy};
      }
      continue;
    }
    // The wake happens while out_mu is held: that keeps the receiver alive (see Hook).
    if (kernel::ActivitySlot* wake = h.receiver->offer(m, h.edge, h.priority, h.policy, h.suppress_window))
      wake->wake();
  }
  // Alive until then: a non-concurrent executor frees a task deleted by a handler only once the
  // handler (here the sender's) is done.
  const auto take_at_once = [&] {
    for (std::size_t i = 0; i < n_at_once; ++i) at_once[i].receiver->take_now(m, at_once[i].edge, at_once[i].policy);
  };
  if (!sinks_due) {
    if (n_at_once > 0) {
      out.unlock();
      take_at_once();
    }
    return;
  }
  // Handed over outside out_mu: a sink may lead into another node (a network writer delivering to
  // a reader of this process on this thread), whose locks must not nest inside this sender's.
  constexpr std::size_t kInline = 4;
  std::shared_ptr<HookSink> inline_due[kInline];
  std::vector<std::shared_ptr<HookSink>> more_due;
  std::size_t n = 0;
  for (detail::Hook& h : from.hooks) {
    if (!h.to_sink || !h.sink->due) continue;
    h.sink->due = false;
    if (n < kInline)
      inline_due[n++] = h.sink->sink;
    else
      more_due.push_back(h.sink->sink);
  }
  out.unlock();
  // The receivers first: their handlers catch what they throw, a sink might not, and a message
  // admitted but never handed over would be lost from the books.
  take_at_once();
  for (std::size_t i = 0; i < n; ++i) inline_due[i]->on_message(m);
  for (const auto& sink : more_due) sink->on_message(m);
}

Status Node::send_as(TaskId sender, Port port, const Payload& payload) {
  std::unique_lock lock(mu_);
  TaskRecord* s = lookup_locked(sender);
  if (s == nullptr) return no_task(sender);
  // The sender's out_mu keeps its record: remove() takes it before the task can be freed. The
  // node lock goes first, so that a send into a busy node does not hold every other caller up.
  std::unique_lock out(s->out_mu);
  lock.unlock();
  const Message m{.source = sender, .port = port, .hops = 0, .time = now(), .payload = payload};
  send_locked(*s, m, out);
  return {};
}

void Node::cut_cycle(TaskRecord& from) {
  // Called from `from`'s on_message, on its own context; a second send of the same handler finds
  // the task faulted already.
  if (from.state.load() != TaskState::kRunning) return;
  // The trail back: each task's last deep message came from the one before it in the cycle.
  constexpr std::size_t kMaxNames = 12;
  std::vector<std::string> trail{from.name};
  std::vector<TaskId> seen{from.id};
  bool closed = false;
  {
    std::lock_guard lock(mu_);
    // The message being handled is more than half way to kMaxHops: its source is `deep_source`.
    const std::uint64_t handled = from.deep_source.load(std::memory_order_relaxed);
    TaskId prev{static_cast<std::uint32_t>(handled >> 32), static_cast<std::uint32_t>(handled)};
    while (seen.size() < kMaxNames) {
      const TaskRecord* r = lookup_locked(prev);
      if (r == nullptr) break;
      trail.push_back(r->name);
      if (std::find(seen.begin(), seen.end(), prev) != seen.end()) {
        closed = true;
        break;
      }
      seen.push_back(prev);
      const std::uint64_t bits = r->deep_source.load(std::memory_order_relaxed);
      prev = TaskId{static_cast<std::uint32_t>(bits >> 32), static_cast<std::uint32_t>(bits)};
    }
  }
  std::string names;
  for (auto it = trail.rbegin(); it != trail.rend(); ++it) names += (names.empty() ? "" : " -> ") + *it;
  if (!closed) names += " (and more)";
  const std::string what = "message cycle " + names + ": more than " + std::to_string(kMaxHops) +
                           " answers in a row, each sent while handling the one before, with no tick or outside "
                           "input between; cut by faulting '" +
                           from.name + "' (a cycle of hooks must not answer every message)";
  {
    std::lock_guard lock(mu_);
    if (cycle_error_.empty()) cycle_error_ = "node '" + config_.name + "': " + what;
  }
  from.fault("on_message", what.c_str());
}

std::string Node::cycle_error() const {
  std::lock_guard lock(mu_);
  return cycle_error_;
}

std::uint32_t Node::longest_chain() const {
  std::lock_guard lock(mu_);
  std::uint16_t n = retired_longest_chain_;
  for (const auto& s : slots_)
    if (s.record) n = std::max(n, s.record->longest_chain.load(std::memory_order_relaxed));
  return n;
}

TrafficCounters Node::traffic() const {
  std::lock_guard lock(mu_);
  TrafficCounters t = retired_;
  for (const auto& s : slots_) {
    if (!s.record) continue;
    TaskRecord& r = *s.record;
    std::lock_guard in(r.in_mu);
    TrafficCounters x = r.traffic;
    x.delivered = r.delivered.load(std::memory_order_relaxed);
    t += x;
  }
  return t;
}

std::uint64_t Node::queued() const {
  std::lock_guard lock(mu_);
  std::uint64_t n = 0;
  for (const auto& s : slots_) {
    if (!s.record) continue;
    std::lock_guard in(s.record->in_mu);
    n += s.record->queue.size();
  }
  return n;
}

void Node::set_tracing(bool on) { tracing_.store(on); }

void Node::set_probe_sink(ProbeSink sink) {
  std::lock_guard lock(probe_mu_);
  probe_sink_ = sink ? std::make_shared<const ProbeSink>(std::move(sink)) : nullptr;
  probing_.store(probe_sink_ != nullptr, std::memory_order_release);
}

void Node::probe(const TaskRecord& from, std::string_view channel, std::span<const float> values) {
  std::shared_ptr<const ProbeSink> sink;
  {
    std::lock_guard lock(probe_mu_);
    sink = probe_sink_;
  }
  // Called outside the lock: a sink may take its own locks or replace itself.
  if (sink) (*sink)(ProbeSample{now(), config_.name, from.name, channel, values});
}

std::uint64_t Node::trace_hash() const {
  std::lock_guard lock(trace_mu_);
  return trace_hash_;
}

void Node::trace(const TaskRecord& receiver, const Message& m) {
  // Word-wise mixing (a 64-bit hash_combine): cheap enough to leave tracing on in every run.
  const auto mix = [](std::uint64_t h, std::uint64_t w) {
    return h ^ (w + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2));
  };
  std::uint64_t w = mix(static_cast<std::uint64_t>(m.time.count()),
                        (std::uint64_t{receiver.id.index} << 32) | receiver.id.generation);
  w = mix(w, (std::uint64_t{m.source.index} << 32) | m.source.generation);
  w = mix(w, (std::uint64_t{m.port} << 8) | m.payload.count);
  const auto n = m.payload.count;
  std::uint32_t bits[Payload::kInlineValues];
  std::memcpy(bits, m.payload.values, n * sizeof(float));
  for (std::size_t i = 0; i + 1 < n; i += 2) w = mix(w, (std::uint64_t{bits[i]} << 32) | bits[i + 1]);
  if (n % 2 != 0) w = mix(w, bits[n - 1]);
  std::lock_guard lock(trace_mu_);
  trace_hash_ = mix(trace_hash_, w) * 0x100000001b3ULL;
}

}  // namespace symb::os
