#include "symb/sim/local_radio.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "symb/os/node.hpp"

namespace symb::sim {

void RadioTask::on_start() { radio_.connect(robot_, &node(), id()); }

void RadioTask::on_stop() { radio_.disconnect(robot_, id()); }

void RadioTask::on_message(const os::Message& m) {
  if (m.source.valid()) {
    radio_.transmit(robot_, m.payload.blob);  // from a hooked task: on air at the next step
  } else {
    send(0, m.payload);  // from the medium (posted): on to the hooked tasks
  }
}

kernel::Result<std::unique_ptr<LocalRadio>> LocalRadio::create(std::size_t robots, LocalRadioOptions options) {
  if (robots == 0) return kernel::Error{"local radio: no robots"};
  if (!(std::isfinite(options.range) && options.range > 0))
    return kernel::Error{"local radio: the range must be a positive number of cm"};
  return std::unique_ptr<LocalRadio>(new LocalRadio(robots, options));
}

void LocalRadio::attach(WorldRunner& runner) {
  runner.add_observer([this](const StepRecord& record) { step(record); });
}

kernel::Result<os::TaskId> LocalRadio::add_to(os::Node& node, std::size_t robot, std::string name) {
  if (robot >= robots_.size())
    return kernel::Error{"local radio: no robot " + std::to_string(robot) + " (" + std::to_string(robots_.size()) +
                         " robots)"};
  // One message per other robot and step, plus room for a few steps' backlog.
  const std::size_t capacity = 4 * robots_.size() + 16;
  return node.create(std::move(name), std::make_unique<RadioTask>(*this, robot),
                     {.priority = 2, .queue_capacity = capacity});
}

void LocalRadio::connect(std::size_t robot, os::Node* node, os::TaskId task) {
  std::lock_guard lock(mu_);
  robots_.at(robot).node = node;
  robots_.at(robot).task = task;
}

void LocalRadio::disconnect(std::size_t robot, os::TaskId task) {
  std::lock_guard lock(mu_);
  Robot& r = robots_.at(robot);
  if (r.task != task) return;  // a newer radio task of the same robot took over
  r.node = nullptr;
  r.task = {};
  r.pending.reset();
}

void LocalRadio::transmit(std::size_t robot, std::shared_ptr<const os::Blob> blob) {
  const io::Bytes* bytes = os::blob_as<io::Bytes>(blob.get());
  std::lock_guard lock(mu_);
  if (bytes == nullptr || bytes->data.size() > options_.max_message_bytes) {
    ++counts_.too_long;
    return;
  }
  Robot& r = robots_.at(robot);
  if (r.pending) ++counts_.overwritten;
  r.pending = std::move(blob);
}

void LocalRadio::step(const StepRecord& record) {
  std::lock_guard lock(mu_);
  const std::size_t n = std::min(robots_.size(), record.robots.size());
  const double range2 = options_.range * options_.range;
  for (std::size_t s = 0; s < n; ++s) {
    Robot& sender = robots_[s];
    if (!sender.pending) continue;
    os::Message m;
    m.payload = os::Payload{static_cast<float>(s)};
    m.payload.blob = std::move(sender.pending);
    sender.pending.reset();
    ++counts_.transmitted;
    const Pose& from = record.robots[s].state.pose;
    for (std::size_t r = 0; r < n; ++r) {
      if (r == s) continue;
      const Pose& to = record.robots[r].state.pose;
      const double dx = to.x - from.x, dy = to.y - from.y;
      if (dx * dx + dy * dy > range2) {
        ++counts_.out_of_range;
        continue;
      }
      Robot& receiver = robots_[r];
      if (receiver.node == nullptr) {
        ++counts_.dropped;
        continue;
      }
      m.time = receiver.node->now();
      if (receiver.node->post(receiver.task, m).ok()) {
        ++counts_.delivered;
        ++receiver.received;
      } else {
        ++counts_.dropped;
      }
    }
  }
}

RadioCounts LocalRadio::counts() const {
  std::lock_guard lock(mu_);
  return counts_;
}

std::uint64_t LocalRadio::received_by(std::size_t robot) const {
  std::lock_guard lock(mu_);
  return robots_.at(robot).received;
}

}  // namespace symb::sim
