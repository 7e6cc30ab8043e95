#include "symb/os/task.hpp"

#include "symb/os/node.hpp"
#include "symb/os/task_record.hpp"
#include "symb/os/task_type_registry.hpp"

namespace symb::os {

kernel::Status Task::on_parameter(std::string_view name, const ParamValue& value) {
  // The node sets record_->params before the task starts and never replaces it.
  const TaskType* type = record_->params ? record_->params->type : nullptr;
  const LiveParam* live = nullptr;
  if (type != nullptr && !type->live.empty())
    for (std::size_t i = 0; i < type->params.size(); ++i)
      if (type->params[i].name == name) live = &type->live[i];
  if (live == nullptr || !live->apply) {
    const std::string what = type != nullptr ? type->name + " task" : "task";
    return kernel::Error{"a running " + what + " keeps its " + std::string(name) +
                         ": create a new task (and rehook) to change it"};
  }
  if (bindings_)
    for (const Binding& b : *bindings_)
      if (b.owner == live->owner) return live->apply(b.object, value, [&] { return on_parameter_changed(name); });
  return kernel::Error{"task type '" + type->name + "' declares '" + std::string(name) +
                       "' live, but its task bound no options that hold it"};
}

Node& Task::node() const { return record_->node; }
TaskId Task::id() const { return record_->id; }
const std::string& Task::name() const { return record_->name; }
kernel::RandomStream& Task::random() { return record_->random; }

std::size_t Task::pending_messages() const {
  std::lock_guard lock(record_->in_mu);
  return record_->queue.size();
}

void Task::send(Port port, const Payload& payload) {
  // Built in one go: a default Message would clear its payload first.
  const Message m{
      .source = record_->id, .port = port, .hops = record_->next_hops, .time = record_->node.now(), .payload = payload};
  record_->node.send_from(*record_, m);
}

void Task::send(Port port, std::span<const float> values) {
  // The numbers go straight into the message (a Payload made first would be copied into it).
  const Message m{.source = record_->id,
                  .port = port,
                  .hops = record_->next_hops,
                  .time = record_->node.now(),
                  .payload = Payload(values)};
  record_->node.send_from(*record_, m);
}

void Task::notify() { record_->notify(true); }

std::uint64_t Task::skip_ticks_before(kernel::Time t) {
  // A handler's own call: the node set the slot before the task started and keeps it until the
  // task is stopped.
  return record_->slot != nullptr ? record_->slot->skip_ticks_before(t) : 0;
}

void Task::probe(std::string_view channel, std::span<const float> values) const {
  if (record_->node.probing()) record_->node.probe(*record_, channel, values);
}

bool Task::probing() const { return record_->node.probing(); }

void Task::log(LogLevel level, std::string_view text) const { record_->node.log().write(level, record_->name, text); }

}  // namespace symb::os
