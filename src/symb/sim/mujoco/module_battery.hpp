// ModuleBatteries: each module's battery in a 3D world, drained by its actuators, shared over the
// organism's docks (the paper's "share energy ... over a common bus system").
//
// Model, per runner tick of length dt (the runner's period), for module m:
//   power = idle + wheel * (|left| + |right|) + hinge * |hinge speed|          (W)
// where left, right are the rim speeds the runner applied during the tick (m/s, ModuleStep::wheels)
// and the hinge speed the one it measured at the tick's end (rad/s); energy -= power * dt, never
// below 0. Then sharing: for every docked pair (a, b) whose batteries both share, in the order
// (lower module, its connector), the fuller gives the emptier
//   min(share_power * dt, (E_fuller - E_emptier) / 2)                          (J)
// so two sharing modules equalise at share_power at most, and nothing crosses an undocked link.
// A module whose energy is 0 after that is unpowered: the runner gives its wheels 0 and holds its
// hinge (MujocoRunner::set_powered), logged once as a warning; when sharing refills it, it is
// powered again (logged).
//
// Device `battery` per module (a sensor): channels charge (fraction of capacity), energy (J),
// power (W, the tick's drain), sharing (0 or 1), published every tick; ioctls share_on,
// share_off, state.
//
// Lifetime: like the organism bus, the batteries must outlive the runner they are attached to.
#pragma once

#include <cstddef>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "symb/kernel/result.hpp"
#include "symb/robot/sensor.hpp"
#include "symb/sim/mujoco/mujoco_runner.hpp"

namespace symb::sim::mujoco {

struct BatteryModel {
  double capacity = 3600;    // J: 7.4 V x 135 mAh
  double idle = 0.5;         // W: electronics, radio, sensors
  double wheel = 4.0;        // W per m/s of rim speed, per wheel
  double hinge = 2.0;        // W per rad/s of hinge speed
  double share_power = 2.0;  // W: the most one docked link moves
};

class ModuleBatteries;

class BatteryDevice final : public robot::Sensor {
 public:
  BatteryDevice(ModuleBatteries& owner, std::size_t module);
  static std::vector<robot::ChannelSpec> channel_specs();
  robot::PublishResult publish_state(const std::array<float, 4>& values, kernel::Time time) {
    return publish(std::span<const float>(values.data(), values.size()), time);
  }
};

class ModuleBatteries {
 public:
  // Every battery starts full, not sharing. Fails for a model with a capacity that is not a
  // positive finite number or a negative coefficient.
  static kernel::Result<std::unique_ptr<ModuleBatteries>> create(MujocoRunner& runner, BatteryModel model = {});
  ModuleBatteries(const ModuleBatteries&) = delete;
  ModuleBatteries& operator=(const ModuleBatteries&) = delete;

  std::shared_ptr<BatteryDevice> device(std::size_t module) const { return devices_.at(module); }
  const BatteryModel& model() const { return model_; }
  double energy(std::size_t module) const;  // J
  // Clamped to [0, capacity]. Throws std::out_of_range for a bad module.
  void set_energy(std::size_t module, double joules);
  bool sharing(std::size_t module) const;
  void set_sharing(std::size_t module, bool on);
  std::string describe(std::size_t module) const;

 private:
  ModuleBatteries(MujocoRunner& runner, BatteryModel model);
  void tick(const MujocoStepRecord& record);

  struct Battery {
    double energy = 0;
    double power = 0;
    bool sharing = false;
    bool empty = false;
  };
  MujocoRunner& runner_;
  const BatteryModel model_;
  const double dt_;
  mutable std::mutex mu_;
  std::vector<Battery> batteries_;
  std::vector<std::shared_ptr<BatteryDevice>> devices_;
  std::vector<std::pair<std::size_t, std::size_t>> links_;  // reused every tick
};

}  // namespace symb::sim::mujoco
