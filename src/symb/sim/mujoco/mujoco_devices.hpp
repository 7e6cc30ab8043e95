// The 3D world's device drivers: the robot layer's Sensor and Actuator for one module of a
// MujocoWorld, the counterparts of sim_drivers.hpp, so that the same device tasks (`sensor`,
// `actuator_sink`) and the controllers above them drive a module as they drive a Thymio. The
// MujocoRunner is their hardware: each tick it applies the newest actuator commands, steps the
// world and publishes the sensors' readings.
//
//   MujocoIrSensor     "ir", 4 channels front, back, left, right: proximity, 0..1, 1 - d / range
//                      for an obstacle d metres from the face's sensor, 0 when nothing is within
//                      its range (or the face has no sensor). Bigger is nearer, as on the Thymio.
//   MujocoHingeSensor  "hinge_state", 2 channels angle (rad), speed (rad/s) of the hinge
//   MujocoHinge        "hinge", 1 channel target (rad, the kind's range): the position servo's
//                      target. Closing it leaves the servo on its last target: a bent organism
//                      that straightened on its own could push its neighbours.
//   SimWheels          "wheels", the 2D driver itself (sim_drivers.hpp): left, right in Thymio
//                      motor units [-500, 500], 500 mapped to the kind's top rim speed, so a
//                      controller written for the full range uses the full range here too.
//   MujocoImuSensor    "imu", 6 channels ax, ay, az (m/s^2, specific force: +9.81 on z at rest),
//                      gx, gy, gz (rad/s), of the module's front half in the module frame; the
//                      acceleration is the mean over the last control period (mujoco_world.hpp).
//   MujocoTouchSensor  "touch", 4 channels front, back, left, right: the normal force (N) of the
//                      contacts on that face, 0 when nothing touches it.
//   MujocoLaser        "laser" (kinds with a laser), one channel per ray, "ray0" the rightmost:
//                      the distance (m) to what the ray meets, the laser's range for nothing.
//   MujocoCamera       "camera" (kinds with a camera), 3 channels nearest (m, the smallest depth
//                      of a pixel that sees a module or an obstacle, the range when none does),
//                      nearest_id (its object id, 0 for none), seen (the share of pixels that
//                      see a module or an obstacle); every sample
//                      carries the frame itself as a robot::DepthImage blob (depth_image.hpp),
//                      which the sensor task forwards in the same message.
// The runner publishes imu, touch, laser and camera only while a task listens to them (their
// rays and contact sums cost nothing otherwise), ir and hinge_state every tick.
//   MujocoConnector    "connector_<name>", one per connector, 6 channels: state (0 free, 1
//                      aligned, 2 docked), open (0 or 1), peer (the docked partner's module index,
//                      -1 when not docked), then its docking beacon (MujocoWorld::beacon): beacon_d
//                      (m, -1 when none is seen), beacon_bearing, beacon_heading (rad, 0 when none). Its ioctls act on
//                      the world at once and answer with its verdict: `open`, `close` (the connector's mechanism:
//                      whether it accepts a dock; closing a docked connector leaves it docked), `latch`, `unlatch` (the
//                      answer is the world's refusal text when refused) and `state`. Every change is
//                      written to the module's node log (and a dock's to its partner's).
//
// The device's own open()/close() (io::Device) is not the connector's mechanism: as for every
// sensor, it says whether samples are taken. The ioctls work either way.
//
// Thread-safe like the 2D drivers: the runner and the tasks (and a shell) may be on different
// threads. Actuators keep their command under a lock of their own; a connector acts on the world
// through the WorldAccess (world_access.hpp), under the world's lock.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "symb/kernel/time.hpp"
#include "symb/robot/actuator.hpp"
#include "symb/robot/channel_spec.hpp"
#include "symb/robot/depth_image.hpp"
#include "symb/robot/sensor.hpp"
#include "symb/sim/mujoco/module_kind.hpp"
#include "symb/sim/mujoco/mujoco_world.hpp"
#include "symb/sim/mujoco/world_access.hpp"

namespace symb::sim::mujoco {

inline constexpr std::size_t kIrFaces = kFaces.size();
using IrProximity = std::array<float, kIrFaces>;  // in kFaces order

// The IR proximity of one face: 1 - distance / range, 0 for nothing (see above).
float ir_proximity(std::optional<double> distance, double range);

class MujocoIrSensor final : public robot::Sensor {
 public:
  explicit MujocoIrSensor(std::string name = "ir");
  static std::vector<robot::ChannelSpec> channel_specs();
  robot::PublishResult publish_readings(const IrProximity& readings, kernel::Time time) {
    return publish(std::span<const float>(readings.data(), readings.size()), time);
  }
};

class MujocoHingeSensor final : public robot::Sensor {
 public:
  explicit MujocoHingeSensor(std::string name = "hinge_state");
  static std::vector<robot::ChannelSpec> channel_specs();
  robot::PublishResult publish_state(double angle, double speed, kernel::Time time) {
    const float v[2] = {static_cast<float>(angle), static_cast<float>(speed)};
    return publish(std::span<const float>(v, 2), time);
  }
};

class MujocoImuSensor final : public robot::Sensor {
 public:
  explicit MujocoImuSensor(std::string name = "imu");
  static std::vector<robot::ChannelSpec> channel_specs();
  robot::PublishResult publish_reading(const ImuReading& r, kernel::Time time);
};

class MujocoTouchSensor final : public robot::Sensor {
 public:
  explicit MujocoTouchSensor(std::string name = "touch");
  static std::vector<robot::ChannelSpec> channel_specs();
  robot::PublishResult publish_forces(const std::array<double, kIrFaces>& force, kernel::Time time);
};

class MujocoLaser final : public robot::Sensor {
 public:
  MujocoLaser(std::string name, const LaserSpec& spec);
  static std::vector<robot::ChannelSpec> channel_specs(const LaserSpec& spec);
  robot::PublishResult publish_scan(std::span<const float> distances, kernel::Time time) {
    return publish(distances, time);
  }
};

class MujocoCamera final : public robot::Sensor {
 public:
  MujocoCamera(std::string name, const CameraSpec& spec);
  static std::vector<robot::ChannelSpec> channel_specs(const CameraSpec& spec);
  // Publishes the frame's summary with the frame attached.
  robot::PublishResult publish_frame(std::shared_ptr<const robot::DepthImage> frame, kernel::Time time);

 private:
  double range_;
};

// The newest hinge command.
struct HingeCommand {
  double target = 0;           // rad
  std::uint64_t sequence = 0;  // commands applied so far; 0: none yet (the servo holds 0)
};

class MujocoHinge final : public robot::Actuator {
 public:
  // `range`: the kind's hinge range (rad).
  MujocoHinge(std::string name, std::array<double, 2> range);
  static std::vector<robot::ChannelSpec> channel_specs(std::array<double, 2> range);
  // What the runner applies at its next tick. Any thread.
  HingeCommand command() const;

 protected:
  kernel::Status apply(std::span<const float> values) override;

 private:
  mutable std::mutex mu_;  // cmd_ (apply runs under the actuator's own lock, this one is inner)
  HingeCommand cmd_;
};

// A connector's reading: state, open, peer, then its docking beacon (mujoco_world.hpp): distance,
// bearing, heading; -1, 0, 0 when it sees none.
inline constexpr std::size_t kConnectorChannels = 6;
using ConnectorReading = std::array<float, kConnectorChannels>;

class MujocoConnector final : public robot::Sensor {
 public:
  // Connector `connector` of module `module` of the world behind `access`.
  MujocoConnector(std::string name, std::shared_ptr<WorldAccess> access, std::size_t module, std::size_t connector);
  static std::vector<robot::ChannelSpec> channel_specs();

  std::size_t module() const { return module_; }
  std::size_t connector() const { return connector_; }

  // The ioctls' actions, for C++ callers: the world's verdict (success or its refusal text).
  kernel::Status latch();
  kernel::Status unlatch();
  kernel::Status set_open(bool open);

  // For the runner, under the world's lock: this connector's reading now.
  ConnectorReading reading(const MujocoWorld& world) const;
  robot::PublishResult publish_reading(const ConnectorReading& reading, kernel::Time time) {
    return publish(std::span<const float>(reading.data(), reading.size()), time);
  }

 private:
  kernel::Status dock(bool latching);
  kernel::Result<std::string> describe();

  std::shared_ptr<WorldAccess> access_;
  const std::size_t module_;
  const std::size_t connector_;
};

}  // namespace symb::sim::mujoco
