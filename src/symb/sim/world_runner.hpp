// WorldRunner: the simulated robots' hardware clock. It is an activity of the executor the
// robots' nodes run on (virtual-time or threads), ticking at the control period, and each tick:
//   1. gives every robot the newest command of its SimWheels,
//   2. steps the world by one period,
//   3. publishes every robot's IR readings to its SimIrSensor, stamped with the node time, and
//      its pose and ground readings to its SimPoseSensor and SimGroundSensor when a task listens
//      to them (most control systems do not: then they cost nothing),
//   4. hands a StepRecord (poses, IR, wheel speeds, contacts) to the observers (CSV writers,
//      trajectory pictures, fitness functions).
//
// A world that can step ahead (World::can_step_ahead: Box2DWorld) has its next step's physics
// begun right after the readings are published, through Executor::run_alongside_lanes: under the
// lockstep executor it runs on one of its threads while the robots' nodes run their window, and
// the next tick only makes the step visible. The same run, bit for bit.
//
// Latency contract: IR published after step k reaches the robot's SensorTask, its controller
// and its ActuatorSinkTask within the same virtual instant, and the wheel command that results
// is used by step k + 1: exactly one control period from reading to action, as on a robot that
// samples, thinks and drives once per period. Under the VirtualTimeExecutor this holds because
// the sensor task drains the sample inside the runner's tick (it takes its notifications at once)
// or, when an event at the instant outranks it, in an activation right after, before any later
// event, and handlers take no virtual time. The runner has a high
// priority so that, at an instant shared with periodic tasks, the world moves first. Under the
// LockstepExecutor the runner is on the main lane and each robot's node on its own lane: the
// readings are published first in the robot's window [t, t + period) as from a handler of its
// lane, so the sensor task takes them at once there too (and the controller and the sink, which
// take their messages at once, run the rest of the chain inside that call; whatever must queue
// runs in the lane's window, in parallel with the other lanes), and step k + 1 at
// t + period reads the wheels after every window has closed: the same instants, so the same run.
// Robot i's devices must feed a node on executor.lane(i) (ScenarioSession builds them so), and
// under a non-concurrent executor nothing else may call them (they have no lock:
// robot::DeviceThreads::kOneAtATime; a shell reaches them as injected work). The runner fills
// the step's records on the executor's threads (parallel()) and publishes robot i's readings
// through for_each_lane_before_its_window(), which may hand lane i to another thread for the call
// and make it first in the lane's window.
// Under the ThreadExecutor everything happens in real time and the same chain takes as long as
// it takes.
//
// Robots are those in the world when the runner is made; add every robot first. The runner owns
// one mutex for the world: it holds it while it steps, and with_world() takes it (and the lock of
// a next step begun early) for anyone else (a shell, a test) who wants to look at the world while
// it runs on another thread.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <vector>

#include "symb/kernel/executor.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"
#include "symb/sim/periodic_runner.hpp"
#include "symb/sim/sim_drivers.hpp"
#include "symb/sim/world.hpp"

namespace symb::sim {

struct RobotStep {
  RobotState state;         // pose after the step; wheel speeds used during it; contacts
  IrReadings ir{};          // what was published to the robot's SimIrSensor
  GroundReadings ground{};  // the floor under its ground sensors (ground_model.hpp)
};

struct StepRecord {
  std::uint64_t step = 0;  // the world's step count after this step (1 for the first)
  kernel::Time time{0};    // node time of the tick
  std::vector<RobotStep> robots;
};

// Called on the runner's execution context after each step. It must not block for long, nor add
// observers; it may call with_world() and stop().
using StepObserver = std::function<void(const StepRecord&)>;

// The life cycle (start, stop, running, error, the period and priority) is PeriodicRunner's.
class WorldRunner final : public PeriodicRunner {
 public:
  // `executor` and `world` must outlive the runner. Throws std::invalid_argument unless the period
  // is in (0, 1 s]. Makes one SimIrSensor ("ir") and one SimWheels ("wheels") per robot.
  WorldRunner(kernel::Executor& executor, World& world) : WorldRunner(executor, world, Options{}) {}
  WorldRunner(kernel::Executor& executor, World& world, Options options);
  // Stops the runner and waits until the executor has let go of it. Destroy it outside the
  // executor's handlers (from the thread that runs a virtual-time executor, between runs).
  ~WorldRunner() override;

  std::size_t robot_count() const { return ir_.size(); }
  // The robot's devices, to hand to its node's tasks. Throw std::out_of_range for a bad index.
  std::shared_ptr<SimIrSensor> ir_sensor(std::size_t robot) const;
  std::shared_ptr<SimWheels> wheels(std::size_t robot) const;
  std::shared_ptr<SimPoseSensor> pose_sensor(std::size_t robot) const;
  std::shared_ptr<SimGroundSensor> ground_sensor(std::size_t robot) const;

  // Any time, any thread.
  void add_observer(StepObserver observer);

  // Steps done by this runner (observers see the step they are told of counted already).
  std::uint64_t steps() const { return steps_.load(std::memory_order_acquire); }

  // Runs `fn(world)` with the world locked: safe against a step running on another thread.
  template <class F>
  decltype(auto) with_world(F&& fn) {
    std::lock_guard lock(world_mu_);
    std::lock_guard physics(physics_mu_);
    return fn(world_);
  }

 private:
  kernel::Status step_once(kernel::Time now) override;

  World& world_;
  const double dt_;  // options().period in seconds
  std::vector<std::shared_ptr<SimIrSensor>> ir_;
  std::vector<std::shared_ptr<SimWheels>> wheels_;
  std::vector<std::shared_ptr<SimPoseSensor>> pose_;
  std::vector<std::shared_ptr<SimGroundSensor>> ground_;
  // Robot i's pose and ground sensor have a listener (ListenedSensor): read at every step.
  std::shared_ptr<std::atomic<bool>[]> pose_heard_, ground_heard_;

  std::mutex world_mu_;
  // Held by the next step's physics begun beside the robots' window (and, innermost, by
  // with_world()): not world_mu_, which the step holds while it hands work to the executor's
  // threads, the very threads that run the physics job.
  std::mutex physics_mu_;
  StepRecord record_;  // reused every tick; only the runner's context touches it

  std::mutex observers_mu_;
  std::vector<StepObserver> observers_;
  std::atomic<bool> has_observers_{false};  // lets a step without observers skip their lock
  std::atomic<std::uint64_t> steps_{0};
};

}  // namespace symb::sim
