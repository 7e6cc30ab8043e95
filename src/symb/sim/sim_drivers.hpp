// Simulated device drivers: the robot layer's Sensor and Actuator for a robot that lives in a
// World. The task graph above them (SensorTask, controllers, ActuatorSinkTask) cannot tell them
// from real hardware drivers; the WorldRunner is their "hardware": it publishes each step's IR
// readings to the SimIrSensor and reads the newest command from the SimWheels.
//
//   SimIrSensor  7 channels ir0..ir6, raw units, [0, kIrMax]: Thymio2's horizontal proximity
//                sensors (see world.hpp for their placement)
//   SimPoseSensor   3 channels x, y (cm), heading (rad, -pi..pi): where the robot is, as an
//                overhead tracker or a motion-capture system would report it
//   SimGroundSensor 2 channels left, right: floor reflectance 0..1 (ground_model.hpp)
//   SimWheels    2 channels left, right, Thymio motor units, [-500, 500]. The real Thymio's
//                firmware takes wheel targets in these units; here 500 is mapped to the simulated
//                top speed kMaxWheelSpeed (16.6 cm/s), linearly, so a controller written for the
//                full range uses the full range. (On a real Thymio 500 is about 20 cm/s.)
//
// All are thread-safe (the runner and the tasks may run on different threads: ThreadExecutor)
// unless made DeviceThreads::kOneAtATime, as the WorldRunner makes them under a non-concurrent
// executor.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "symb/kernel/time.hpp"
#include "symb/robot/actuator.hpp"
#include "symb/robot/channel_spec.hpp"
#include "symb/robot/sensor.hpp"
#include "symb/sim/ground_model.hpp"
#include "symb/sim/world.hpp"

namespace symb::sim {

// Thymio motor units at full speed, and their scale to the world's cm/s.
inline constexpr float kWheelUnitsMax = 500.0f;
inline constexpr double kCmPerSecondPerWheelUnit = kMaxWheelSpeed / kWheelUnitsMax;

inline double wheel_units_to_cm_per_s(double units) { return units * kCmPerSecondPerWheelUnit; }
inline double cm_per_s_to_wheel_units(double cm_per_s) { return cm_per_s / kCmPerSecondPerWheelUnit; }

class SimIrSensor final : public robot::Sensor {
 public:
  explicit SimIrSensor(std::string name = "ir", robot::DeviceThreads threads = robot::DeviceThreads::kAny);

  static std::vector<robot::ChannelSpec> channel_specs();
  // For the runner: one reading of all 7 sensors at node time `time`.
  robot::PublishResult publish_readings(const IrReadings& readings, kernel::Time time) {
    return publish(std::span<const float>(readings.data(), readings.size()), time);
  }
};

// A simulated sensor whose has_listener() is mirrored into `heard`, a flag of the world runner's
// (none: not mirrored): a runner that publishes a pose or ground reading only to a sensor some
// task listens to reads its robots' flags from one dense array, not from every robot's sensor
// object at every step. Shared: a task may hold the sensor after the runner is gone.
class ListenedSensor : public robot::Sensor {
 protected:
  ListenedSensor(std::string name, std::vector<robot::ChannelSpec> channels, std::shared_ptr<std::atomic<bool>> heard,
                 robot::DeviceThreads threads)
      : robot::Sensor(std::move(name), std::move(channels), {.threads = threads}), heard_(std::move(heard)) {}
  void on_listener_changed(bool listening) override {
    if (heard_) heard_->store(listening, std::memory_order_relaxed);
  }

 private:
  std::shared_ptr<std::atomic<bool>> heard_;
};

class SimPoseSensor final : public ListenedSensor {
 public:
  // The channels' ranges are the arena's (plus a margin: a pose is never clamped). `heard`: see
  // ListenedSensor.
  SimPoseSensor(std::string name, double arena_width, double arena_height,
                std::shared_ptr<std::atomic<bool>> heard = nullptr,
                robot::DeviceThreads threads = robot::DeviceThreads::kAny);

  static std::vector<robot::ChannelSpec> channel_specs(double arena_width, double arena_height);
  robot::PublishResult publish_pose(const Pose& pose, kernel::Time time) {
    const float v[3] = {static_cast<float>(pose.x), static_cast<float>(pose.y), static_cast<float>(pose.theta)};
    return publish(std::span<const float>(v, 3), time);
  }
};

class SimGroundSensor final : public ListenedSensor {
 public:
  // `heard`: see ListenedSensor.
  explicit SimGroundSensor(std::string name = "ground", std::shared_ptr<std::atomic<bool>> heard = nullptr,
                           robot::DeviceThreads threads = robot::DeviceThreads::kAny);

  static std::vector<robot::ChannelSpec> channel_specs();
  robot::PublishResult publish_readings(const GroundReadings& readings, kernel::Time time) {
    return publish(std::span<const float>(readings.data(), readings.size()), time);
  }
};

// The newest wheel command, in the world's units.
struct WheelCommand {
  double left = 0;             // cm/s
  double right = 0;            // cm/s
  std::uint64_t sequence = 0;  // commands applied so far; 0: none yet (the wheels stand still)
};

class SimWheels final : public robot::Actuator {
 public:
  explicit SimWheels(std::string name = "wheels", robot::DeviceThreads threads = robot::DeviceThreads::kAny);

  static std::vector<robot::ChannelSpec> channel_specs();
  // What the runner applies at its next step. Any thread (for kOneAtATime, the device's context).
  WheelCommand command() const;
  // Closing the device stops the wheels, as a motor driver that loses its enable line does.
  void close() override;

 protected:
  // `values` are conditioned already (clamped to +-500, no NaN): scale and hand over.
  kernel::Status apply(std::span<const float> values) override;

 private:
  WheelCommand cmd_;  // under apply_mutex()
};

}  // namespace symb::sim
