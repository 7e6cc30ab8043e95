#include "symb/sim/scenario_events.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "symb/os/node.hpp"
#include "symb/sim/world_runner.hpp"

namespace symb::sim {

ScenarioEvents::ScenarioEvents(kernel::Executor& executor, std::vector<EventSpec> events, std::vector<Robot> robots)
    : executor_(executor), events_(std::move(events)), robots_(std::move(robots)), shells_(robots_.size()) {
  std::stable_sort(events_.begin(), events_.end(), [](const EventSpec& a, const EventSpec& b) { return a.at < b.at; });
  for (const EventSpec& e : events_)
    if (e.robot >= robots_.size() || robots_[e.robot].node == nullptr)
      throw std::out_of_range("scenario events: no robot " + std::to_string(e.robot));
}

ScenarioEvents::~ScenarioEvents() {
  stop();
  // stop() waits under the thread executor; a virtual-time executor outside its run has released
  // us already.
  std::unique_lock lock(mu_);
  released_cv_.wait(lock, [&] { return !attached_; });
}

kernel::Status ScenarioEvents::start() {
  {
    std::lock_guard lock(mu_);
    if (attached_) return kernel::Error{"the scenario's events are already running"};
    attached_ = true;
  }
  // No period yet: on_activity_start sets the gap to the first event.
  executor_.attach(*this, kernel::ActivityOptions{kEventPriority, kernel::Duration{0}, "events"});
  return {};
}

void ScenarioEvents::stop() {
  kernel::ActivitySlot* slot = nullptr;
  {
    std::lock_guard lock(mu_);
    if (!attached_) return;
    slot = slot_;
    slot_ = nullptr;
  }
  if (slot != nullptr) slot->detach();
  if (executor_.concurrent()) {
    std::unique_lock lock(mu_);
    released_cv_.wait(lock, [&] { return !attached_; });
  }
}

std::size_t ScenarioEvents::done() const {
  std::lock_guard lock(mu_);
  return done_;
}

std::size_t ScenarioEvents::failed() const {
  std::lock_guard lock(mu_);
  return failed_;
}

void ScenarioEvents::on_activity_attached(kernel::ActivitySlot& slot) {
  std::lock_guard lock(mu_);
  slot_ = &slot;
}

void ScenarioEvents::on_activity_start() {
  start_ = executor_.clock().now();
  run_due();
}

void ScenarioEvents::on_activity_tick() { run_due(); }

void ScenarioEvents::on_activity_released() {
  std::lock_guard lock(mu_);
  slot_ = nullptr;
  attached_ = false;
  released_cv_.notify_all();
}

void ScenarioEvents::run_due() {
  const kernel::Time now = executor_.clock().now();
  while (next_ < events_.size() && start_ + events_[next_].at <= now) {
    const EventSpec& e = events_[next_++];
    const Robot& robot = robots_[e.robot];
    if (!shells_[e.robot]) {
      shell::Shell::Options options;
      options.devices = robot.devices;
      if (robot.serve) robot.serve(options);
      shells_[e.robot] = std::make_unique<shell::Shell>(*robot.node, std::move(options));
    }
    const shell::Reply reply = shells_[e.robot]->execute(e.line);
    std::string text = e.line;
    if (!reply.text.empty()) {
      std::string answer = reply.text;
      while (!answer.empty() && answer.back() == '\n') answer.pop_back();
      text += answer.find('\n') == std::string::npos ? ": " + answer : ":\n" + answer;
    } else {
      text += ": ok";
    }
    robot.node->log().write(reply.ok ? os::LogLevel::kInfo : os::LogLevel::kError, kEventLogSource, text);
    std::lock_guard lock(mu_);
    ++done_;
    if (!reply.ok) ++failed_;
  }
  // The slot is used outside the lock: a detach may release this activity at once.
  kernel::ActivitySlot* slot = nullptr;
  const bool last = next_ == events_.size();
  {
    std::lock_guard lock(mu_);
    slot = slot_;
    if (last) slot_ = nullptr;
  }
  if (slot == nullptr) return;
  if (last)
    slot->detach();
  else
    slot->set_period(start_ + events_[next_].at - now);
}

std::shared_ptr<const shell::DeviceTable> world_runner_devices(const WorldRunner& runner, std::size_t robot) {
  auto table = std::make_shared<shell::DeviceTable>();
  const std::shared_ptr<io::Device> devices[] = {runner.ir_sensor(robot), runner.wheels(robot),
                                                 runner.pose_sensor(robot), runner.ground_sensor(robot)};
  for (const auto& d : devices)
    if (d) (*table)[d->name()] = d;
  return table;
}

}  // namespace symb::sim
