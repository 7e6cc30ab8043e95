#include "symb/sim/mujoco/mujoco_devices.hpp"

#include <algorithm>
#include <stdexcept>

namespace symb::sim::mujoco {

float ir_proximity(std::optional<double> distance, double range) {
  if (!distance || range <= 0) return 0.0f;
  return static_cast<float>(std::clamp(1.0 - *distance / range, 0.0, 1.0));
}

std::vector<robot::ChannelSpec> MujocoIrSensor::channel_specs() {
  std::vector<robot::ChannelSpec> c;
  for (const Face face : kFaces) c.push_back(robot::ChannelSpec{face_name(face), "proximity", 0.0f, 1.0f});
  return c;
}

MujocoIrSensor::MujocoIrSensor(std::string name) : robot::Sensor(std::move(name), channel_specs()) {}

std::vector<robot::ChannelSpec> MujocoHingeSensor::channel_specs() {
  // Wide enough never to clamp a real reading: a hinge limit is soft, and a docked organism can
  // whip a joint round fast.
  return {robot::ChannelSpec{"angle", "rad", -4.0f, 4.0f}, robot::ChannelSpec{"speed", "rad/s", -1000.0f, 1000.0f}};
}

MujocoHingeSensor::MujocoHingeSensor(std::string name) : robot::Sensor(std::move(name), channel_specs()) {}

std::vector<robot::ChannelSpec> MujocoHinge::channel_specs(std::array<double, 2> range) {
  return {robot::ChannelSpec{"target", "rad", static_cast<float>(range[0]), static_cast<float>(range[1])}};
}

MujocoHinge::MujocoHinge(std::string name, std::array<double, 2> range)
    : robot::Actuator(std::move(name), channel_specs(range)) {}

HingeCommand MujocoHinge::command() const {
  std::lock_guard lock(mu_);
  return cmd_;
}

kernel::Status MujocoHinge::apply(std::span<const float> values) {
  std::lock_guard lock(mu_);
  cmd_.target = values[0];
  ++cmd_.sequence;
  return {};
}

// --- MujocoConnector ---------------------------------------------------------------------------

std::vector<robot::ChannelSpec> MujocoConnector::channel_specs() {
  return {robot::ChannelSpec{"state", "0 free, 1 aligned, 2 docked", 0.0f, 2.0f},
          robot::ChannelSpec{"open", "flag", 0.0f, 1.0f},
          robot::ChannelSpec{"peer", "module index, -1 none", -1.0f, 16777216.0f}};
}

MujocoConnector::MujocoConnector(std::string name, std::shared_ptr<WorldAccess> access, std::size_t module,
                                 std::size_t connector)
    : robot::Sensor(std::move(name), channel_specs()),
      access_(std::move(access)),
      module_(module),
      connector_(connector) {
  if (!access_) throw std::invalid_argument("connector '" + this->name() + "': no world");
  if (module_ >= access_->module_count())
    throw std::out_of_range("connector '" + this->name() + "': no module " + std::to_string(module_));
  if (connector_ >= access_->connector_count(module_))
    throw std::out_of_range("connector '" + this->name() + "': module " + std::to_string(module_) +
                            " has no connector " + std::to_string(connector_));
  add_ioctl({"open", std::nullopt, "opens the connector: it accepts a dock (answers its state)"},
            [this](const os::ParamValue*) -> kernel::Result<std::string> {
              if (auto st = set_open(true); !st) return kernel::Error{st.error()};
              return describe();
            });
  add_ioctl({"close", std::nullopt, "closes the connector: it refuses new docks; a dock it has stays"},
            [this](const os::ParamValue*) -> kernel::Result<std::string> {
              if (auto st = set_open(false); !st) return kernel::Error{st.error()};
              return describe();
            });
  add_ioctl({"latch", std::nullopt, "docks to the connector facing this one, or answers why not"},
            [this](const os::ParamValue*) -> kernel::Result<std::string> {
              if (auto st = latch(); !st) return kernel::Error{st.error()};
              return describe();
            });
  add_ioctl({"unlatch", std::nullopt, "undocks, or answers why not"},
            [this](const os::ParamValue*) -> kernel::Result<std::string> {
              if (auto st = unlatch(); !st) return kernel::Error{st.error()};
              return describe();
            });
  add_ioctl({"state", std::nullopt, "free, aligned or docked (to whom), and open or closed"},
            [this](const os::ParamValue*) { return describe(); });
}

std::array<float, 3> MujocoConnector::reading(const MujocoWorld& world) const {
  const auto peer = world.docked_to(module_, connector_);
  return {static_cast<float>(world.connector_state(module_, connector_)),
          world.is_open(module_, connector_) ? 1.0f : 0.0f, peer ? static_cast<float>(peer->first) : -1.0f};
}

kernel::Status MujocoConnector::latch() { return dock(true); }
kernel::Status MujocoConnector::unlatch() { return dock(false); }

kernel::Status MujocoConnector::dock(bool latching) {
  kernel::Status verdict;
  std::vector<DockEvent> events;
  const bool reached = access_->with_world([&](MujocoWorld& world) {
    verdict = latching ? world.latch(module_, connector_) : world.unlatch(module_, connector_);
    events = access_->take_dock_events(world);
  });
  if (!reached) return kernel::Error{"connector '" + name() + "': the world is gone"};
  // Outside the world's lock: a log sink may take its time.
  access_->log_dock_events(events);
  return verdict;
}

kernel::Status MujocoConnector::set_open(bool open) {
  bool changed = false;
  const bool reached = access_->with_world([&](MujocoWorld& world) {
    changed = world.is_open(module_, connector_) != open;
    world.set_open(module_, connector_, open);
  });
  if (!reached) return kernel::Error{"connector '" + name() + "': the world is gone"};
  if (changed) access_->log(module_, os::LogLevel::kInfo, name(), open ? "opened" : "closed");
  return {};
}

kernel::Result<std::string> MujocoConnector::describe() {
  std::string text;
  const bool reached = access_->with_world([&](MujocoWorld& world) {
    text = state_name(world.connector_state(module_, connector_));
    if (const auto peer = world.docked_to(module_, connector_))
      text +=
          " to " + world.module(peer->first).name + "." + world.module(peer->first).kind.connectors[peer->second].name;
    text += world.is_open(module_, connector_) ? ", open" : ", closed";
  });
  if (!reached) return kernel::Error{"connector '" + name() + "': the world is gone"};
  return text;
}

}  // namespace symb::sim::mujoco
