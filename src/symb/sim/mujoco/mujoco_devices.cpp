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

std::vector<robot::ChannelSpec> MujocoImuSensor::channel_specs() {
  // Wide enough for a module knocked about by its neighbours; a reading beyond is clamped.
  constexpr float kMaxAcceleration = 1000, kMaxRate = 1000;
  std::vector<robot::ChannelSpec> c;
  for (const char* axis : {"ax", "ay", "az"}) c.push_back({axis, "m/s^2", -kMaxAcceleration, kMaxAcceleration});
  for (const char* axis : {"gx", "gy", "gz"}) c.push_back({axis, "rad/s", -kMaxRate, kMaxRate});
  return c;
}

MujocoImuSensor::MujocoImuSensor(std::string name) : robot::Sensor(std::move(name), channel_specs()) {}

robot::PublishResult MujocoImuSensor::publish_reading(const ImuReading& r, kernel::Time time) {
  const float v[6] = {static_cast<float>(r.acceleration[0]),     static_cast<float>(r.acceleration[1]),
                      static_cast<float>(r.acceleration[2]),     static_cast<float>(r.angular_velocity[0]),
                      static_cast<float>(r.angular_velocity[1]), static_cast<float>(r.angular_velocity[2])};
  return publish(std::span<const float>(v, 6), time);
}

std::vector<robot::ChannelSpec> MujocoTouchSensor::channel_specs() {
  std::vector<robot::ChannelSpec> c;
  for (const Face face : kFaces) c.push_back(robot::ChannelSpec{face_name(face), "N", 0.0f, 1.0e6f});
  return c;
}

MujocoTouchSensor::MujocoTouchSensor(std::string name) : robot::Sensor(std::move(name), channel_specs()) {}

robot::PublishResult MujocoTouchSensor::publish_forces(const std::array<double, kIrFaces>& force, kernel::Time time) {
  std::array<float, kIrFaces> v{};
  for (std::size_t i = 0; i < kIrFaces; ++i) v[i] = static_cast<float>(force[i]);
  return publish(std::span<const float>(v.data(), v.size()), time);
}

std::vector<robot::ChannelSpec> MujocoLaser::channel_specs(const LaserSpec& spec) {
  std::vector<robot::ChannelSpec> c;
  for (std::size_t r = 0; r < spec.rays; ++r)
    c.push_back(robot::ChannelSpec{"ray" + std::to_string(r), "m", 0.0f, static_cast<float>(spec.range)});
  return c;
}

MujocoLaser::MujocoLaser(std::string name, const LaserSpec& spec)
    : robot::Sensor(std::move(name), channel_specs(spec)) {}

std::vector<robot::ChannelSpec> MujocoCamera::channel_specs(const CameraSpec& spec) {
  return {robot::ChannelSpec{"nearest", "m", 0.0f, static_cast<float>(spec.range)},
          robot::ChannelSpec{"nearest_id", "object id", -16777216.0f, 16777216.0f},
          robot::ChannelSpec{"seen", "share of pixels", 0.0f, 1.0f}};
}

MujocoCamera::MujocoCamera(std::string name, const CameraSpec& spec)
    : robot::Sensor(std::move(name), channel_specs(spec)), range_(spec.range) {}

robot::PublishResult MujocoCamera::publish_frame(std::shared_ptr<const robot::DepthImage> frame, kernel::Time time) {
  float nearest = static_cast<float>(range_);
  std::int32_t nearest_id = kNothingId;
  std::size_t seen = 0;
  for (std::size_t p = 0; p < frame->depth.size(); ++p) {
    if (frame->ids[p] == kNothingId) continue;
    ++seen;
    if (frame->depth[p] < nearest) {
      nearest = frame->depth[p];
      nearest_id = frame->ids[p];
    }
  }
  const float v[3] = {nearest, static_cast<float>(nearest_id),
                      frame->depth.empty() ? 0.0f : static_cast<float>(seen) / static_cast<float>(frame->depth.size())};
  return publish(std::span<const float>(v, 3), std::move(frame), time);
}

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
          robot::ChannelSpec{"peer", "module index, -1 none", -1.0f, 16777216.0f},
          robot::ChannelSpec{"beacon_d", "m, -1 none", -1.0f, static_cast<float>(kBeaconRange)},
          robot::ChannelSpec{"beacon_bearing", "rad", -3.1416f, 3.1416f},
          robot::ChannelSpec{"beacon_heading", "rad", -3.1416f, 3.1416f}};
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

ConnectorReading MujocoConnector::reading(const MujocoWorld& world) const {
  const auto peer = world.docked_to(module_, connector_);
  const auto b = world.beacon(module_, connector_);
  return {static_cast<float>(world.connector_state(module_, connector_)),
          world.is_open(module_, connector_) ? 1.0f : 0.0f,
          peer ? static_cast<float>(peer->first) : -1.0f,
          b ? static_cast<float>(b->distance) : -1.0f,
          b ? static_cast<float>(b->bearing) : 0.0f,
          b ? static_cast<float>(b->heading) : 0.0f};
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
