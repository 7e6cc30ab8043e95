#include "symb/sim/sim_drivers.hpp"

namespace symb::sim {

std::vector<robot::ChannelSpec> SimIrSensor::channel_specs() {
  std::vector<robot::ChannelSpec> c;
  for (std::size_t i = 0; i < kIrCount; ++i)
    c.push_back(robot::ChannelSpec{"ir" + std::to_string(i), "raw", 0.0f, static_cast<float>(kIrMax)});
  return c;
}

SimIrSensor::SimIrSensor(std::string name, robot::DeviceThreads threads)
    : robot::Sensor(std::move(name), channel_specs(), {.threads = threads}) {}

std::vector<robot::ChannelSpec> SimPoseSensor::channel_specs(double arena_width, double arena_height) {
  const float margin = 100.0f;
  return {robot::ChannelSpec{"x", "cm", -margin, static_cast<float>(arena_width) + margin},
          robot::ChannelSpec{"y", "cm", -margin, static_cast<float>(arena_height) + margin},
          robot::ChannelSpec{"heading", "rad", -4.0f, 4.0f}};
}

SimPoseSensor::SimPoseSensor(std::string name, double arena_width, double arena_height,
                             std::shared_ptr<std::atomic<bool>> heard, robot::DeviceThreads threads)
    : ListenedSensor(std::move(name), channel_specs(arena_width, arena_height), std::move(heard), threads) {}

std::vector<robot::ChannelSpec> SimGroundSensor::channel_specs() {
  return {robot::ChannelSpec{"left", "reflectance", 0.0f, 1.0f},
          robot::ChannelSpec{"right", "reflectance", 0.0f, 1.0f}};
}

SimGroundSensor::SimGroundSensor(std::string name, std::shared_ptr<std::atomic<bool>> heard,
                                 robot::DeviceThreads threads)
    : ListenedSensor(std::move(name), channel_specs(), std::move(heard), threads) {}

std::vector<robot::ChannelSpec> SimWheels::channel_specs() {
  return {robot::ChannelSpec{"left", "thymio", -kWheelUnitsMax, kWheelUnitsMax},
          robot::ChannelSpec{"right", "thymio", -kWheelUnitsMax, kWheelUnitsMax}};
}

SimWheels::SimWheels(std::string name, robot::DeviceThreads threads)
    : robot::Actuator(std::move(name), channel_specs(), threads) {}

WheelCommand SimWheels::command() const {
  std::lock_guard lock(apply_mutex());
  return cmd_;
}

void SimWheels::close() {
  robot::Actuator::close();
  std::lock_guard lock(apply_mutex());
  cmd_.left = cmd_.right = 0;
}

kernel::Status SimWheels::apply(std::span<const float> values) {
  // Under apply_mutex(), held by Actuator::set. A close() that raced with this command wins: the
  // wheels of a closed device stand still.
  if (!is_open()) return kernel::Error{"closed while the command was applied"};
  cmd_.left = wheel_units_to_cm_per_s(values[0]);
  cmd_.right = wheel_units_to_cm_per_s(values[1]);
  ++cmd_.sequence;
  return {};
}

}  // namespace symb::sim
