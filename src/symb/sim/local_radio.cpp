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
  // Room for a few steps' messages from every other robot, up to kMaxQueue: a queue's slots are
  // allocated up front (176 bytes each), and 4 per robot of a swarm of 10,000 would be 7 MB per
  // robot, 70 GB in all.
  const std::size_t capacity = std::min(4 * robots_.size() + 16, kMaxQueue);
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
  Slot& slot = slots_[robot];
  std::lock_guard slot_lock(slot.mu);
  slot.pending.reset();
}

void LocalRadio::transmit(std::size_t robot, std::shared_ptr<const os::Blob> blob) {
  const io::Bytes* bytes = os::blob_as<io::Bytes>(blob.get());
  Slot& slot = slots_.at(robot);
  std::lock_guard lock(slot.mu);
  if (bytes == nullptr || bytes->data.size() > options_.max_message_bytes) {
    ++slot.too_long;
    return;
  }
  if (slot.pending) ++slot.overwritten;
  slot.pending = std::move(blob);
}

void LocalRadio::find_receivers(std::size_t sender) {
  const double range2 = options_.range * options_.range;
  const Pose& from = positions_[sender];
  // The same test for every pair: a distance that is NaN is not "farther than range".
  auto in_range = [&](std::size_t r) {
    const double dx = positions_[r].x - from.x, dy = positions_[r].y - from.y;
    return !(dx * dx + dy * dy > range2);
  };
  if (!std::isfinite(from.x) || !std::isfinite(from.y)) {
    for (std::size_t r = 0; r < positions_.size(); ++r)
      if (r != sender && in_range(r)) receivers_.push_back(r);
    return;
  }
  const double range = options_.range;
  grid_.for_each({from.x - range, from.y - range, from.x + range, from.y + range}, [&](std::size_t r) {
    if (r != sender && std::isfinite(positions_[r].x) && std::isfinite(positions_[r].y) && in_range(r))
      receivers_.push_back(r);
  });
  for (std::size_t r : strays_)
    if (r != sender && in_range(r)) receivers_.push_back(r);
  std::sort(receivers_.begin(), receivers_.end());
}

void LocalRadio::step(const StepRecord& record) {
  std::lock_guard lock(mu_);
  const std::size_t n = std::min(robots_.size(), record.robots.size());
  // What goes on air: each robot's pending message, taken at once so that a transmit() running
  // meanwhile (ThreadExecutor) goes to the next step whole.
  outgoing_.resize(n);
  std::size_t senders = 0;
  for (std::size_t s = 0; s < n; ++s) {
    Slot& slot = slots_[s];
    std::lock_guard slot_lock(slot.mu);
    outgoing_[s] = std::move(slot.pending);
    slot.pending.reset();
    if (outgoing_[s]) ++senders;
  }
  if (senders == 0) return;
  positions_.resize(n);
  strays_.clear();
  for (std::size_t i = 0; i < n; ++i) {
    positions_[i] = record.robots[i].state.pose;
    if (!std::isfinite(positions_[i].x) || !std::isfinite(positions_[i].y)) strays_.push_back(i);
  }
  grid_.layout(SpatialGrid::bounds(positions_), options_.range, 4 * n + 64);
  grid_.set_points(positions_);
  for (std::size_t s = 0; s < n; ++s) {
    if (!outgoing_[s]) continue;
    os::Message m;
    m.payload = os::Payload{static_cast<float>(s)};
    m.payload.blob = std::move(outgoing_[s]);
    outgoing_[s].reset();
    ++counts_.transmitted;
    receivers_.clear();
    find_receivers(s);
    counts_.out_of_range += (n - 1) - receivers_.size();
    for (std::size_t r : receivers_) deliver_locked(r, s, m);
  }
}

void LocalRadio::deliver_locked(std::size_t r, std::size_t sender, os::Message& m) {
  Robot& receiver = robots_[r];
  bool delivered = false;
  if (receiver.relay) {
    delivered = receiver.relay(sender, m.payload.blob);
  } else if (receiver.node != nullptr) {
    m.time = receiver.node->now();
    delivered = receiver.node->post(receiver.task, m).ok();
  }
  if (delivered) {
    ++counts_.delivered;
    ++receiver.received;
  } else {
    ++counts_.dropped;
  }
}

void LocalRadio::relay(std::size_t robot, Relay relay) {
  std::lock_guard lock(mu_);
  robots_.at(robot).relay = std::move(relay);
}

std::shared_ptr<const os::Blob> LocalRadio::take_pending(std::size_t robot) {
  Slot& slot = slots_.at(robot);
  std::lock_guard lock(slot.mu);
  return std::exchange(slot.pending, nullptr);
}

bool LocalRadio::deliver(std::size_t robot, std::size_t sender, std::shared_ptr<const os::Blob> blob) {
  std::lock_guard lock(mu_);
  if (robot >= robots_.size()) return false;
  os::Message m;
  m.payload = os::Payload{static_cast<float>(sender)};
  m.payload.blob = std::move(blob);
  const std::uint64_t before = counts_.delivered;
  deliver_locked(robot, sender, m);
  return counts_.delivered != before;
}

RadioCounts LocalRadio::counts() const {
  std::lock_guard lock(mu_);
  RadioCounts c = counts_;
  for (const Slot& slot : slots_) {
    std::lock_guard slot_lock(slot.mu);
    c.overwritten += slot.overwritten;
    c.too_long += slot.too_long;
  }
  return c;
}

std::uint64_t LocalRadio::received_by(std::size_t robot) const {
  std::lock_guard lock(mu_);
  return robots_.at(robot).received;
}

}  // namespace symb::sim
