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
// Latency contract: IR published after step k reaches the robot's SensorTask, its controller
// and its ActuatorSinkTask within the same virtual instant, and the wheel command that results
// is used by step k + 1: exactly one control period from reading to action, as on a robot that
// samples, thinks and drives once per period. Under the VirtualTimeExecutor this holds because
// the sensor's notification is injected work, which the executor runs right after the runner's
// tick and before any later event, and handlers take no virtual time. The runner has a high
// priority so that, at an instant shared with periodic tasks, the world moves first. Under the
// ThreadExecutor everything happens in real time and the same chain takes as long as it takes.
//
// Robots are those in the world when the runner is made; add every robot first. The runner owns
// one mutex for the world: it holds it while it steps, and with_world() takes it for anyone else
// (a shell, a test) who wants to look at the world while it runs on another thread.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "symb/kernel/executor.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"
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

class WorldRunner final : private kernel::Activity {
 public:
  struct Options {
    kernel::Duration period = std::chrono::milliseconds(30);  // 33.33 Hz, the paper's control rate
    int priority = 100;                                       // above every control task
    std::string name = "world";
  };

  // `executor` and `world` must outlive the runner. Throws std::invalid_argument unless the period
  // is in (0, 1 s]. Makes one SimIrSensor ("ir") and one SimWheels ("wheels") per robot.
  WorldRunner(kernel::Executor& executor, World& world) : WorldRunner(executor, world, Options{}) {}
  WorldRunner(kernel::Executor& executor, World& world, Options options);
  // Stops the runner and waits until the executor has let go of it. Destroy it outside the
  // executor's handlers (from the thread that runs a virtual-time executor, between runs).
  ~WorldRunner() override;
  WorldRunner(const WorldRunner&) = delete;
  WorldRunner& operator=(const WorldRunner&) = delete;

  std::size_t robot_count() const { return ir_.size(); }
  // The robot's devices, to hand to its node's tasks. Throw std::out_of_range for a bad index.
  std::shared_ptr<SimIrSensor> ir_sensor(std::size_t robot) const;
  std::shared_ptr<SimWheels> wheels(std::size_t robot) const;
  std::shared_ptr<SimPoseSensor> pose_sensor(std::size_t robot) const;
  std::shared_ptr<SimGroundSensor> ground_sensor(std::size_t robot) const;

  // Any time, any thread.
  void add_observer(StepObserver observer);

  // Attaches the runner to the executor: the first step comes one period later. Fails when it is
  // already running.
  kernel::Status start();
  // Detaches it. Under the thread executor, called from another thread, returns once the last
  // tick has finished; otherwise (from the runner's own observer, or under the virtual-time
  // executor inside a run) the last tick may still be under way. A stopped runner may start again.
  void stop();
  bool running() const;

  // Steps done by this runner.
  std::uint64_t steps() const { return steps_.load(std::memory_order_acquire); }
  const Options& options() const { return options_; }
  // Why the runner stopped on its own (the world threw), or empty.
  std::string error() const;

  // Runs `fn(world)` with the world locked: safe against a step running on another thread.
  template <class F>
  decltype(auto) with_world(F&& fn) {
    std::lock_guard lock(world_mu_);
    return fn(world_);
  }

 private:
  void on_activity_attached(kernel::ActivitySlot& slot) override;
  void on_activity_start() override;
  void on_activity_input() override {}
  void on_activity_tick() override;
  void on_activity_stop() override {}
  void on_activity_released() override;
  void tick();

  kernel::Executor& executor_;
  World& world_;
  const Options options_;
  const double dt_;  // options_.period in seconds
  std::vector<std::shared_ptr<SimIrSensor>> ir_;
  std::vector<std::shared_ptr<SimWheels>> wheels_;
  std::vector<std::shared_ptr<SimPoseSensor>> pose_;
  std::vector<std::shared_ptr<SimGroundSensor>> ground_;

  std::mutex world_mu_;
  StepRecord record_;  // reused every tick; only the runner's context touches it

  std::mutex observers_mu_;
  std::vector<StepObserver> observers_;
  std::atomic<bool> has_observers_{false};  // lets a step without observers skip their lock

  mutable std::mutex state_mu_;  // slot_, attached_, error_
  std::condition_variable released_cv_;
  kernel::ActivitySlot* slot_ = nullptr;
  bool attached_ = false;  // between attach and on_activity_released
  std::string error_;
  std::atomic<std::thread::id> runner_thread_{};
  std::atomic<std::uint64_t> steps_{0};
};

}  // namespace symb::sim
