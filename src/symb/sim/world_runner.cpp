#include "symb/sim/world_runner.hpp"

#include <stdexcept>

#include "symb/kernel/parallel_for.hpp"
#include "symb/kernel/prefetch.hpp"

namespace symb::sim {

namespace {
// How many robots ahead a loop over the robots asks for their state (kernel/prefetch.hpp).
constexpr std::size_t kPrefetchAhead = 4;
}  // namespace

WorldRunner::WorldRunner(kernel::Executor& executor, World& world, Options options)
    : PeriodicRunner(executor, std::move(options)),
      world_(world),
      dt_(std::chrono::duration<double>(this->options().period).count()) {
  const std::size_t n = world_.robot_count();
  // Under a non-concurrent executor every call to these devices comes from its contexts, one at a
  // time: this runner's handler and robot i's node on lane i, each in its own phase of a window.
  const auto threads = executor.concurrent() ? robot::DeviceThreads::kAny : robot::DeviceThreads::kOneAtATime;
  pose_heard_ = std::shared_ptr<std::atomic<bool>[]>(new std::atomic<bool>[n]());
  ground_heard_ = std::shared_ptr<std::atomic<bool>[]>(new std::atomic<bool>[n]());
  for (std::size_t i = 0; i < n; ++i) {
    ir_.push_back(std::make_shared<SimIrSensor>("ir", threads));
    wheels_.push_back(std::make_shared<SimWheels>("wheels", threads));
    // Each sensor shares the array and points at its own flag (the aliasing constructor).
    pose_.push_back(std::make_shared<SimPoseSensor>(
        "pose", world_.spec().width, world_.spec().height,
        std::shared_ptr<std::atomic<bool>>(pose_heard_, &pose_heard_[static_cast<std::ptrdiff_t>(i)]), threads));
    ground_.push_back(std::make_shared<SimGroundSensor>(
        "ground", std::shared_ptr<std::atomic<bool>>(ground_heard_, &ground_heard_[static_cast<std::ptrdiff_t>(i)]),
        threads));
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
      // In a large swarm each robot's wheels are a load from memory: asked for a few robots ahead.
      if (i + kPrefetchAhead < wheels_.size())
        kernel::prefetch_bytes(wheels_[i + kPrefetchAhead].get(), sizeof(SimWheels));
      const WheelCommand c = wheels_[i]->command();
      world_.set_wheels(i, c.left, c.right);
    }
    world_.step(dt_);
    record_.step = world_.steps();
    record_.time = now;
    // Each robot's record from the world's const reads alone: independent jobs.
    const auto fill = [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) {
        RobotStep& r = record_.robots[i];
        r.state = world_.state(i);
        r.ir = world_.ir(i);
        r.ground = ground_readings(world_.spec(), r.state.pose);
      }
    };
    if (kernel::ParallelFor* parallel = executor().parallel())
      parallel->run(record_.robots.size(), fill);
    else
      fill(0, record_.robots.size());
  }
  // Outside the world lock: under the thread executor this runs the sensor tasks' injected work
  // right here, and a handler further down the chain may well look at the world. Robot i's
  // devices feed a node on lane i, so the publishing may be spread over the lanes' threads, each
  // robot's at the start of its lane's window (the record is not written again before then).
  executor().for_each_lane_before_its_window(ir_.size(), [this, now](std::size_t i) {
    const RobotStep& r = record_.robots[i];
    ir_[i]->publish_readings(r.ir, now);
    if (pose_heard_[i].load(std::memory_order_relaxed)) pose_[i]->publish_pose(r.state.pose, now);
    if (ground_heard_[i].load(std::memory_order_relaxed)) ground_[i]->publish_readings(r.ground, now);
  });
  // The next step's physics needs nothing the robots are about to decide (their commands act one
  // step later): under the lockstep executor it runs beside their nodes' window.
  if (world_.can_step_ahead())
    executor().run_alongside_lanes([this] {
      std::lock_guard lock(physics_mu_);
      world_.begin_next_step(dt_);
    });
  // One writer (this handler): a plain store, not a locked read-modify-write per step.
  steps_.store(steps_.load(std::memory_order_relaxed) + 1, std::memory_order_release);
  if (!has_observers_.load(std::memory_order_acquire)) return {};
  std::lock_guard lock(observers_mu_);
  for (const StepObserver& observer : observers_) observer(record_);
  return {};
}

}  // namespace symb::sim
