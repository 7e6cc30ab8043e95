#include "symb/sim/mujoco/mujoco_runner.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "symb/os/node.hpp"

namespace symb::sim::mujoco {

namespace {

constexpr std::int64_t kMjRunnerStepNs = 2'000'000;  // kTimestep in nanoseconds
static_assert(kTimestep == 0.002, "kMjRunnerStepNs must follow the model's time step");

}  // namespace

MujocoRunner::MujocoRunner(kernel::Executor& executor, MujocoWorld& world, Options options)
    : PeriodicRunner(executor, std::move(options)),
      access_(std::make_shared<WorldAccess>(world)),
      period_ns_(std::chrono::duration_cast<std::chrono::nanoseconds>(this->options().period).count()),
      unpowered_(world.module_count()) {
  // The world is read here, before the runner can tick; afterwards only under access_'s lock.
  const std::size_t n = world.module_count();
  record_.modules.resize(n);
  for (std::size_t m = 0; m < n; ++m) {
    const ModuleKind& kind = world.module(m).kind;
    ir_.push_back(std::make_shared<MujocoIrSensor>("ir"));
    hinge_state_.push_back(std::make_shared<MujocoHingeSensor>("hinge_state"));
    hinge_.push_back(std::make_shared<MujocoHinge>("hinge", kind.hinge.range));
    wheels_.push_back(kind.has_wheels ? std::make_shared<SimWheels>("wheels") : nullptr);
    wheel_speed_max_.push_back(kind.has_wheels ? kind.wheels.max_speed : 0.0);
    std::vector<std::shared_ptr<MujocoConnector>> connectors;
    for (std::size_t c = 0; c < kind.connectors.size(); ++c)
      connectors.push_back(
          std::make_shared<MujocoConnector>(connector_device_name(kind.connectors[c].name), access_, m, c));
    connector_readings_.emplace_back(connectors.size());
    connector_listened_.emplace_back(connectors.size(), false);
    connectors_.push_back(std::move(connectors));
    imu_.push_back(std::make_shared<MujocoImuSensor>("imu"));
    touch_.push_back(std::make_shared<MujocoTouchSensor>("touch"));
    laser_.push_back(kind.laser ? std::make_shared<MujocoLaser>("laser", *kind.laser) : nullptr);
    camera_.push_back(kind.camera ? std::make_shared<MujocoCamera>("camera", *kind.camera) : nullptr);
    laser_readings_.emplace_back(kind.laser ? kind.laser->rays : 0);
    for (const Face face : kFaces) {
      const auto sensor =
          std::find_if(kind.ir.begin(), kind.ir.end(), [&](const IrSpec& ir) { return ir.face == face; });
      ir_range_.push_back(sensor == kind.ir.end() ? 0.0 : sensor->range);
    }
  }
  listened_.resize(n);
  imu_readings_.resize(n);
  touch_readings_.resize(n);
  camera_frames_.resize(n);
}

MujocoRunner::~MujocoRunner() {
  halt();
  access_->close();
}

namespace {

template <class T>
const std::shared_ptr<T>& mj_runner_at(const std::vector<std::shared_ptr<T>>& v, std::size_t module) {
  if (module >= v.size()) throw std::out_of_range("mujoco runner: no module " + std::to_string(module));
  return v[module];
}

}  // namespace

std::shared_ptr<MujocoIrSensor> MujocoRunner::ir_sensor(std::size_t module) const { return mj_runner_at(ir_, module); }
std::shared_ptr<MujocoHingeSensor> MujocoRunner::hinge_sensor(std::size_t module) const {
  return mj_runner_at(hinge_state_, module);
}
std::shared_ptr<MujocoHinge> MujocoRunner::hinge(std::size_t module) const { return mj_runner_at(hinge_, module); }
std::shared_ptr<SimWheels> MujocoRunner::wheels(std::size_t module) const { return mj_runner_at(wheels_, module); }

std::shared_ptr<MujocoImuSensor> MujocoRunner::imu(std::size_t module) const { return mj_runner_at(imu_, module); }
std::shared_ptr<MujocoTouchSensor> MujocoRunner::touch(std::size_t module) const {
  return mj_runner_at(touch_, module);
}
std::shared_ptr<MujocoLaser> MujocoRunner::laser(std::size_t module) const { return mj_runner_at(laser_, module); }
std::shared_ptr<MujocoCamera> MujocoRunner::camera(std::size_t module) const { return mj_runner_at(camera_, module); }

std::shared_ptr<MujocoConnector> MujocoRunner::connector(std::size_t module, std::size_t connector) const {
  (void)mj_runner_at(ir_, module);
  const auto& list = connectors_[module];
  if (connector >= list.size())
    throw std::out_of_range("mujoco runner: module " + std::to_string(module) + " has no connector " +
                            std::to_string(connector));
  return list[connector];
}

std::shared_ptr<MujocoConnector> MujocoRunner::connector(std::size_t module, std::string_view name) const {
  (void)mj_runner_at(ir_, module);
  const std::string device = connector_device_name(name);
  for (const auto& c : connectors_[module])
    if (c->name() == device) return c;
  return nullptr;
}

std::vector<std::shared_ptr<io::Device>> MujocoRunner::devices(std::size_t module) const {
  std::vector<std::shared_ptr<io::Device>> all{ir_sensor(module), hinge_sensor(module), hinge(module)};
  if (wheels_[module]) all.push_back(wheels_[module]);
  all.push_back(imu_[module]);
  all.push_back(touch_[module]);
  if (laser_[module]) all.push_back(laser_[module]);
  if (camera_[module]) all.push_back(camera_[module]);
  for (const auto& c : connectors_[module]) all.push_back(c);
  return all;
}

robot::RobotDevices MujocoRunner::device_lookups(std::size_t module) const {
  std::vector<std::shared_ptr<robot::Sensor>> sensors{ir_sensor(module), hinge_sensor(module), imu(module),
                                                      touch(module)};
  if (laser_[module]) sensors.push_back(laser_[module]);
  if (camera_[module]) sensors.push_back(camera_[module]);
  for (const auto& c : connectors_[module]) sensors.push_back(c);
  std::vector<std::shared_ptr<robot::Actuator>> actuators{hinge(module)};
  if (wheels_[module]) actuators.push_back(wheels_[module]);
  return device_lookups_of(std::move(sensors), std::move(actuators));
}

robot::RobotDevices device_lookups_of(std::vector<std::shared_ptr<robot::Sensor>> sensors,
                                      std::vector<std::shared_ptr<robot::Actuator>> actuators) {
  robot::RobotDevices lookups;
  lookups.sensor = [sensors](std::string_view name) -> std::shared_ptr<robot::Sensor> {
    for (const auto& s : sensors)
      if (s->name() == name) return s;
    return nullptr;
  };
  lookups.actuator = [actuators](std::string_view name) -> std::shared_ptr<robot::Actuator> {
    for (const auto& a : actuators)
      if (a->name() == name) return a;
    return nullptr;
  };
  return lookups;
}

void MujocoRunner::add_observer(MujocoStepObserver observer) {
  std::lock_guard lock(observers_mu_);
  observers_.push_back(std::move(observer));
  has_observers_.store(true, std::memory_order_release);
}

kernel::Status MujocoRunner::step_once(kernel::Time now) {
  // The steps due by the end of this tick, from this runner's start, in whole steps.
  const std::uint64_t due =
      static_cast<std::uint64_t>((static_cast<std::int64_t>(ticks_done_ + 1) * period_ns_) / kMjRunnerStepNs);
  const std::uint64_t substeps = due - steps_done_;
  for (std::size_t m = 0; m < connectors_.size(); ++m)
    for (std::size_t c = 0; c < connectors_[m].size(); ++c)
      connector_listened_[m][c] = connectors_[m][c]->has_listener();
  for (std::size_t m = 0; m < listened_.size(); ++m)
    listened_[m] = {imu_[m]->has_listener(), touch_[m]->has_listener(), laser_[m] && laser_[m]->has_listener(),
                    camera_[m] && camera_[m]->has_listener()};
  kernel::Status stepped;
  std::vector<DockEvent> events;
  access_->with_world([&](MujocoWorld& world) {
    for (std::size_t m = 0; m < record_.modules.size(); ++m) {
      ModuleStep& r = record_.modules[m];
      const bool powered = unpowered_[m].load(std::memory_order_relaxed) == 0;
      r.hinge_target = powered ? hinge_[m]->command().target : world.hinge_angle(m);
      world.set_hinge_target(m, r.hinge_target);
      if (wheels_[m]) {
        const WheelCommand c = wheels_[m]->command();
        const double scale = wheel_speed_max_[m] / kWheelUnitsMax;
        r.wheels = {cm_per_s_to_wheel_units(c.left) * scale, cm_per_s_to_wheel_units(c.right) * scale};
        if (!powered) r.wheels = {0, 0};
        if (auto st = world.set_wheels(m, r.wheels[0], r.wheels[1]); !st) {
          stepped = st;
          return;
        }
      }
    }
    stepped = world.step(substeps);
    events = access_->take_dock_events(world);
    if (!stepped) return;
    for (std::size_t m = 0; m < record_.modules.size(); ++m) {
      ModuleStep& r = record_.modules[m];
      r.pose = world.pose(m);
      r.hinge_angle = world.hinge_angle(m);
      r.hinge_speed = world.hinge_speed(m);
      for (std::size_t f = 0; f < kIrFaces; ++f)
        r.ir[f] = ir_proximity(world.ir(m, kFaces[f]), ir_range_[m * kIrFaces + f]);
      for (std::size_t c = 0; c < connectors_[m].size(); ++c)
        if (connector_listened_[m][c]) connector_readings_[m][c] = connectors_[m][c]->reading(world);
      const Listened& l = listened_[m];
      if (l.imu) imu_readings_[m] = world.imu(m);
      if (l.touch) touch_readings_[m] = world.touch(m);
      if (l.laser) world.laser(m, laser_readings_[m]);
      if (l.camera) {
        const CameraSpec& spec = *world.module(m).kind.camera;
        auto frame = std::make_shared<robot::DepthImage>(spec.width, spec.height);
        world.camera(m, frame->depth, frame->ids);
        camera_frames_[m] = std::move(frame);
      }
    }
  });
  access_->log_dock_events(events);
  if (!stepped) return kernel::Error{"world step failed: " + stepped.error()};
  steps_done_ = due;
  ++ticks_done_;
  record_.step = steps_done_;
  record_.time = now;
  // Outside the world lock: under the thread executor this runs the sensor tasks' injected work
  // right here, and a handler further down the chain may well look at the world.
  for (std::size_t m = 0; m < record_.modules.size(); ++m) {
    const ModuleStep& r = record_.modules[m];
    ir_[m]->publish_readings(r.ir, now);
    hinge_state_[m]->publish_state(r.hinge_angle, r.hinge_speed, now);
    for (std::size_t c = 0; c < connectors_[m].size(); ++c)
      if (connector_listened_[m][c]) connectors_[m][c]->publish_reading(connector_readings_[m][c], now);
    const Listened& l = listened_[m];
    if (l.imu) imu_[m]->publish_reading(imu_readings_[m], now);
    if (l.touch) touch_[m]->publish_forces(touch_readings_[m], now);
    if (l.laser) laser_[m]->publish_scan(laser_readings_[m], now);
    if (l.camera) camera_[m]->publish_frame(std::move(camera_frames_[m]), now);
  }
  if (!has_observers_.load(std::memory_order_acquire)) return {};
  std::lock_guard lock(observers_mu_);
  for (const MujocoStepObserver& observer : observers_) observer(record_);
  return {};
}

void MujocoRunner::on_failed(const std::string& error) {
  access_->log_all(os::LogLevel::kError, options().name, error);
}

}  // namespace symb::sim::mujoco
