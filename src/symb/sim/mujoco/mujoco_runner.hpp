// MujocoRunner: the 3D world's hardware clock, the counterpart of the 2D WorldRunner. It is an
// activity of the executor the modules' nodes run on (virtual-time or threads), ticking at the
// control period, and each tick:
//   1. gives every module the newest command of its hinge and (with wheels) its wheels,
//   2. steps the world by the period's whole 2 ms steps (kTimestep): the steps due at the tick's
//      end, counted in integer nanoseconds from the start, so a period that is no multiple of
//      2 ms (33.33 Hz) never drifts: its ticks take 16 or 17 steps, never 16.67,
//   3. publishes every module's IR and hinge state to its MujocoIrSensor and MujocoHingeSensor,
//      stamped with the node time, and each connector's, IMU's, touch's, laser's and camera's
//      reading when a task listens to it (nobody listening: no rays cast, no frame made),
//   4. writes the docking changes since the last tick to the modules' node logs (a latch from a
//      shell or a scenario through with_world is logged like one from a connector's ioctl),
//   5. hands a MujocoStepRecord (poses, hinge, IR) to the observers.
// Latency: as in the 2D runner, readings published after tick k drive the commands used by tick
// k + 1 under the virtual-time executor, one control period from reading to action.
//
// Divergence: a world step that fails (MujocoWorld::step's error) stops the runner; error() then
// says why, every attached node's log has it (error level), and the executor goes on with the
// tasks alone: a run never hangs on a failed world. A failed world stays failed.
//
// Nodes: one per module, made by the caller (its own clock view, log and random streams, e.g.
// seeded with robot_node_seed(seed, index)) and attached with set_node() so that its log hears
// of its module's docking changes. A node must be detached (set_node(m, nullptr)) or outlive the
// runner. The world must outlive the runner; its devices may outlive both (a connector's ioctl
// then answers that the world is gone).
//
//   kernel::VirtualTimeExecutor ex;
//   MujocoRunner runner(ex, world);                  // world: a MujocoWorld
//   os::Node node(ex, {"a", robot_node_seed(seed, 0)});
//   runner.set_node(0, &node);
//   node.create("hinge", std::make_unique<robot::ActuatorSinkTask>(runner.hinge(0)));
//   runner.start();
//   ex.run_for(1s);
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "symb/kernel/executor.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"
#include "symb/robot/robot_task_types.hpp"
#include "symb/sim/mujoco/mujoco_devices.hpp"
#include "symb/sim/mujoco/mujoco_world.hpp"
#include "symb/sim/mujoco/world_access.hpp"
#include "symb/sim/periodic_runner.hpp"
#include "symb/sim/sim_drivers.hpp"

namespace symb::os {
class Node;
}

namespace symb::sim::mujoco {

struct ModuleStep {
  Pose3 pose;
  double hinge_angle = 0;          // rad
  double hinge_speed = 0;          // rad/s
  double hinge_target = 0;         // rad, the command used during the step
  std::array<double, 2> wheels{};  // rim speeds commanded during the step, m/s
  IrProximity ir{};                // what was published to the module's MujocoIrSensor
};

struct MujocoStepRecord {
  std::uint64_t step = 0;  // the world's step count after this tick
  kernel::Time time{0};    // node time of the tick
  std::vector<ModuleStep> modules;
};

// Called on the runner's execution context after each tick. It must not block for long, nor add
// observers; it may call with_world() and stop().
using MujocoStepObserver = std::function<void(const MujocoStepRecord&)>;

// Lookups by device name over the given devices (RobotDevices for the robot task types): what a
// module's node binds to, whoever holds the devices (this runner, or a board's serial line).
robot::RobotDevices device_lookups_of(std::vector<std::shared_ptr<robot::Sensor>> sensors,
                                      std::vector<std::shared_ptr<robot::Actuator>> actuators);

class MujocoRunner final : public PeriodicRunner {
 public:
  // `executor` and `world` must outlive the runner. Throws std::invalid_argument unless the period
  // is in (0, 1 s]. Makes every module's devices.
  MujocoRunner(kernel::Executor& executor, MujocoWorld& world) : MujocoRunner(executor, world, Options{}) {}
  MujocoRunner(kernel::Executor& executor, MujocoWorld& world, Options options);
  // Stops the runner, waits until the executor has let go of it, and closes the world's access.
  // Destroy it outside the executor's handlers.
  ~MujocoRunner() override;

  std::size_t module_count() const { return ir_.size(); }
  // The module's devices, to hand to its node's tasks. Throw std::out_of_range for a bad index.
  std::shared_ptr<MujocoIrSensor> ir_sensor(std::size_t module) const;
  std::shared_ptr<MujocoHingeSensor> hinge_sensor(std::size_t module) const;
  std::shared_ptr<MujocoHinge> hinge(std::size_t module) const;
  // Null for a kind without wheels.
  std::shared_ptr<SimWheels> wheels(std::size_t module) const;
  std::shared_ptr<MujocoImuSensor> imu(std::size_t module) const;
  std::shared_ptr<MujocoTouchSensor> touch(std::size_t module) const;
  // Null for a kind without a laser (a camera).
  std::shared_ptr<MujocoLaser> laser(std::size_t module) const;
  std::shared_ptr<MujocoCamera> camera(std::size_t module) const;
  std::shared_ptr<MujocoConnector> connector(std::size_t module, std::size_t connector) const;
  // By the connector's name in the kind ("front"); null when there is none.
  std::shared_ptr<MujocoConnector> connector(std::size_t module, std::string_view name) const;
  // Every device of the module, for a shell's `devices` list.
  std::vector<std::shared_ptr<io::Device>> devices(std::size_t module) const;
  // The module's devices by name for the robot task types (robot_task_types.hpp), so a shell, a
  // scenario or a genome creates `sensor device=hinge_state` or `actuator_sink device=hinge` on
  // the module's node as on a Thymio's: sensors ir, hinge_state, imu, touch, laser and camera
  // (when the kind has them), connector_<name>; actuators hinge, wheels. The lookups hold the
  // devices, not the runner.
  robot::RobotDevices device_lookups(std::size_t module) const;

  // See the header's Nodes paragraph. Throws std::out_of_range for a bad module.
  void set_node(std::size_t module, os::Node* node) { access_->set_node(module, node); }

  // Any time, any thread.
  void add_observer(MujocoStepObserver observer);

  // An unpowered module (its battery is empty: module_battery.hpp) gets no drive: from its next
  // tick its wheels' commands are taken as 0 and its hinge holds the angle it has. Any thread.
  // Throws std::out_of_range for a bad module.
  void set_powered(std::size_t module, bool powered) { unpowered_.at(module) = powered ? 0 : 1; }
  bool powered(std::size_t module) const { return unpowered_.at(module) == 0; }

  // Runs `fn(world)` with the world locked: safe against a tick running on another thread. False
  // (fn not run) never happens while the runner lives.
  template <class F>
  bool with_world(F&& fn) {
    return access_->with_world(std::forward<F>(fn));
  }
  const std::shared_ptr<WorldAccess>& access() const { return access_; }

 private:
  kernel::Status step_once(kernel::Time now) override;
  void on_failed(const std::string& error) override;

  std::shared_ptr<WorldAccess> access_;
  const std::int64_t period_ns_;
  std::uint64_t steps_done_ = 0;  // by this runner; only its tick touches it
  std::uint64_t ticks_done_ = 0;
  std::vector<double> wheel_speed_max_;  // per module, m/s; 0 without wheels
  std::vector<std::shared_ptr<MujocoIrSensor>> ir_;
  std::vector<std::shared_ptr<MujocoHingeSensor>> hinge_state_;
  std::vector<std::shared_ptr<MujocoHinge>> hinge_;
  std::vector<std::shared_ptr<SimWheels>> wheels_;
  std::vector<std::vector<std::shared_ptr<MujocoConnector>>> connectors_;
  std::vector<std::vector<ConnectorReading>> connector_readings_;  // reused every tick
  std::vector<std::vector<bool>> connector_listened_;              // reused every tick
  std::vector<double> ir_range_;  // per module and face (module * 4 + face), m; 0 without a sensor
  std::vector<std::shared_ptr<MujocoImuSensor>> imu_;
  std::vector<std::shared_ptr<MujocoTouchSensor>> touch_;
  std::vector<std::shared_ptr<MujocoLaser>> laser_;    // null without a laser
  std::vector<std::shared_ptr<MujocoCamera>> camera_;  // null without a camera
  // Per module, reused every tick: which of imu, touch, laser, camera a task listens to, and the
  // readings taken under the world's lock for publishing outside it.
  struct Listened {
    bool imu = false, touch = false, laser = false, camera = false;
  };
  std::vector<Listened> listened_;
  std::vector<ImuReading> imu_readings_;
  std::vector<std::array<double, kIrFaces>> touch_readings_;
  std::vector<std::vector<float>> laser_readings_;
  std::vector<std::shared_ptr<robot::DepthImage>> camera_frames_;

  MujocoStepRecord record_;  // reused every tick; only the runner's context touches it
  std::mutex observers_mu_;
  std::vector<MujocoStepObserver> observers_;
  std::atomic<bool> has_observers_{false};
  std::vector<std::atomic<std::uint8_t>> unpowered_;  // per module: 1 while its battery is empty
};

}  // namespace symb::sim::mujoco
