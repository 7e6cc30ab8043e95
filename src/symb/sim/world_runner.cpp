#include "symb/sim/world_runner.hpp"

#include <stdexcept>

namespace symb::sim {

WorldRunner::WorldRunner(kernel::Executor& executor, World& world, Options options)
    : PeriodicRunner(executor, std::move(options)),
      world_(world),
      dt_(std::chrono::duration<double>(this->options().period).count()) {
  const std::size_t n = world_.robot_count();
  for (std::size_t i = 0; i < n; ++i) {
    ir_.push_back(std::make_shared<SimIrSensor>("ir"));
    wheels_.push_back(std::make_shared<SimWheels>("wheels"));
    pose_.push_back(std::make_shared<SimPoseSensor>("pose", world_.spec().width, world_.spec().height));
    ground_.push_back(std::make_shared<SimGroundSensor>("ground"));
  }
  record_.robots.resize(n);
}

WorldRunner::~WorldRunner() { halt(); }

std::shared_ptr<SimIrSensor> WorldRunner::ir_sensor(std::size_t robot) const {
  if (robot >= ir_.size()) throw std::out_of_range("world runner: no robot " + std::to_string(robot));
  return ir_[robot];
}

std::shared_ptr<SimWheels> WorldRunner::wheels(std::size_t robot) const {
  if (robot >= wheels_.size()) throw std::out_of_range("world runner: no robot " + std::to_string(robot));
  return wheels_[robot];
}

std::shared_ptr<SimPoseSensor> WorldRunner::pose_sensor(std::size_t robot) const {
  if (robot >= pose_.size()) throw std::out_of_range("world runner: no robot " + std::to_string(robot));
  return pose_[robot];
}

std::shared_ptr<SimGroundSensor> WorldRunner::ground_sensor(std::size_t robot) const {
  if (robot >= ground_.size()) throw std::out_of_range("world runner: no robot " + std::to_string(robot));
  return ground_[robot];
}

void WorldRunner::add_observer(StepObserver observer) {
  std::lock_guard lock(observers_mu_);
  observers_.push_back(std::move(observer));
  has_observers_.store(true, std::memory_order_release);
}

kernel::Status WorldRunner::step_once(kernel::Time now) {
  {
    std::lock_guard lock(world_mu_);
    for (std::size_t i = 0; i < wheels_.size(); ++i) {
      const WheelCommand c = wheels_[i]->command();
      world_.set_wheels(i, c.left, c.right);
    }
    world_.step(dt_);
    record_.step = world_.steps();
    record_.time = now;
    for (std::size_t i = 0; i < record_.robots.size(); ++i) {
      record_.robots[i].state = world_.state(i);
      record_.robots[i].ir = world_.ir(i);
      record_.robots[i].ground = ground_readings(world_.spec(), record_.robots[i].state.pose);
    }
  }
  // Outside the world lock: under the thread executor this runs the sensor tasks' injected work
  // right here, and a handler further down the chain may well look at the world.
  for (std::size_t i = 0; i < ir_.size(); ++i) {
    const RobotStep& r = record_.robots[i];
    ir_[i]->publish_readings(r.ir, now);
    if (pose_[i]->has_listener()) pose_[i]->publish_pose(r.state.pose, now);
    if (ground_[i]->has_listener()) ground_[i]->publish_readings(r.ground, now);
  }
  // One writer (this handler): a plain store, not a locked read-modify-write per step.
  steps_.store(steps_.load(std::memory_order_relaxed) + 1, std::memory_order_release);
  if (!has_observers_.load(std::memory_order_acquire)) return {};
  std::lock_guard lock(observers_mu_);
  for (const StepObserver& observer : observers_) observer(record_);
  return {};
}

}  // namespace symb::sim
