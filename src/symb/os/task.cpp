#include "symb/os/task.hpp"

#include "symb/os/node.hpp"
#include "symb/os/task_record.hpp"

namespace symb::os {

kernel::Status Task::on_parameter(std::string_view name, const ParamValue& /*value*/) {
  return kernel::Error{"task does not accept a new '" + std::string(name) + "' while it runs"};
}

Node& Task::node() const { return record_->node; }
TaskId Task::id() const { return record_->id; }
const std::string& Task::name() const { return record_->name; }
kernel::Time Task::now() const { return record_->node.now(); }
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

void Task::probe(std::string_view channel, std::span<const float> values) const {
  if (record_->node.probing()) record_->node.probe(*record_, channel, values);
}

bool Task::probing() const { return record_->node.probing(); }

void Task::log(LogLevel level, std::string_view text) const { record_->node.log().write(level, record_->name, text); }

}  // namespace symb::os
