#include "symb/sim/robot_system.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "symb/control/control_task_types.hpp"
#include "symb/evo/evo_task_types.hpp"
#include "symb/robot/ports.hpp"
#include "symb/robot/robot_task_types.hpp"
#include "symb/sim/local_radio.hpp"

namespace symb::sim {

namespace {

constexpr std::uintmax_t kMaxProgramBytes = 1 << 20;
kernel::Error at(const SourceLocation& where, const std::string& what) { return {where.str() + ": " + what}; }

}  // namespace

os::PortDeclaration device_task_ports(std::string_view task) {
  namespace layout = robot::layout;
  // A sensor reads nothing from hooks (a board's link feeds its ir task, but declares no outputs).
  const std::vector<os::PortSpec> reads_nothing{{robot::kDataPort, "none", os::kNoMessages}};
  if (task == kIrTaskName) return {reads_nothing, {{robot::kDataPort, "ir", layout::kSensorVector}}};
  if (task == kGroundTaskName) return {reads_nothing, {{robot::kDataPort, "ground", layout::kSensorVector}}};
  if (task == kPoseTaskName) return {reads_nothing, {{robot::kDataPort, "pose", layout::kPose}}};
  if (task == kWheelsTaskName) return {{{robot::kDataPort, "wheels", layout::kWheelCommand}}, {}};
  if (task == kHingeStateTaskName) return {reads_nothing, {{robot::kDataPort, "hinge_state", layout::kSensorVector}}};
  // Its own layout, so that a wheel command (two numbers in motor units) cannot be hooked into a hinge.
  if (task == kHingeTaskName) return {{{robot::kDataPort, "hinge", layout::kJointTarget}}, {}};
  if (task.substr(0, kConnectorTaskPrefix.size()) == kConnectorTaskPrefix)
    return {reads_nothing, {{robot::kDataPort, "connector", layout::kSensorVector}}};
  return {};
}

std::uint64_t robot_node_seed(std::uint64_t seed, std::size_t index) {
  std::uint64_t z = seed + 0x9e3779b97f4a7c15ULL * (index + 1);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

ProgramReader file_program_reader(std::string base_dir) {
  return [base = std::move(base_dir)](std::string_view ref) -> kernel::Result<std::string> {
    namespace fs = std::filesystem;
    if (ref.empty()) return kernel::Error{"no program file named"};
    fs::path p{std::string(ref)};
    if (p.is_relative() && !base.empty()) p = fs::path(base) / p;
    std::error_code ec;
    const auto size = fs::file_size(p, ec);
    if (ec) return kernel::Error{"cannot read program '" + p.string() + "': " + ec.message()};
    if (size > kMaxProgramBytes)
      return kernel::Error{"program '" + p.string() + "' is larger than 1 MiB (" + std::to_string(size) + " bytes)"};
    std::ifstream in(p, std::ios::binary);
    if (!in) return kernel::Error{"cannot open program '" + p.string() + "'"};
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
  };
}

namespace {

// What a 2D robot's device task types look up: the runner's devices by task name.
robot::RobotDevices device_lookups(const RobotDevices& devices) {
  robot::RobotDevices lookups;
  lookups.sensor = [devices](std::string_view name) -> std::shared_ptr<robot::Sensor> {
    if (name == kIrTaskName) return devices.ir;
    if (name == kPoseTaskName) return devices.pose;
    if (name == kGroundTaskName) return devices.ground;
    return nullptr;
  };
  lookups.actuator = [wheels = devices.wheels](std::string_view name) -> std::shared_ptr<robot::Actuator> {
    return name == kWheelsTaskName ? wheels : nullptr;
  };
  return lookups;
}

kernel::Status register_device_free_types(os::TaskTypeRegistry& registry, ProgramReader read_program) {
  control::ControlResources resources;
  resources.read_program = std::move(read_program);
  if (auto st = control::register_control_task_types(registry, resources); !st) return st;
  return evo::register_evo_task_types(registry, resources);
}

}  // namespace

kernel::Result<std::shared_ptr<const os::TaskTypeRegistry>> shared_scenario_task_types(ProgramReader read_program) {
  return shared_scenario_task_types(std::move(read_program), {});
}

kernel::Result<std::shared_ptr<const os::TaskTypeRegistry>> shared_scenario_task_types(
    ProgramReader read_program, const std::function<kernel::Status(os::TaskTypeRegistry&)>& more) {
  auto registry = std::make_shared<os::TaskTypeRegistry>();
  if (auto st = register_device_free_types(*registry, std::move(read_program)); !st) return kernel::Error{st.error()};
  if (more)
    if (auto st = more(*registry); !st) return kernel::Error{st.error()};
  return std::shared_ptr<const os::TaskTypeRegistry>(std::move(registry));
}

kernel::Status register_scenario_task_types(os::TaskTypeRegistry& registry, RobotDevices devices,
                                            ProgramReader read_program) {
  control::ControlResources resources;
  resources.read_program = std::move(read_program);
  if (devices.module) {
    // Controllers that command a device by name (MDL2e `device` actions, the `dock_seek` task's
    // connector ioctls) find the module's sensors and actuators.
    resources.device = [m = *devices.module](std::string_view name) -> std::shared_ptr<io::Device> {
      if (m.sensor)
        if (auto s = m.sensor(name)) return s;
      if (m.actuator)
        if (auto a = m.actuator(name)) return a;
      return nullptr;
    };
    if (auto s = robot::register_robot_task_types(registry, *devices.module); !s) return s;
    if (auto st = control::register_control_task_types(registry, resources); !st) return st;
    return evo::register_evo_task_types(registry, resources);
  }
  if (auto s = robot::register_robot_task_types(registry, device_lookups(devices)); !s) return s;
  return register_device_free_types(registry, std::move(resources.read_program));
}

kernel::Result<std::unique_ptr<RobotSystem>> RobotSystem::build(kernel::Executor& executor, const RobotSpec& spec,
                                                                RobotDevices devices, RobotSystemOptions options) {
  std::unique_ptr<RobotSystem> sys(new RobotSystem());
  sys->name_ = spec.name;
  if (options.shared_types && !devices.module) {
    // Its own registry over the shared types: its device tasks' types hold its own devices.
    sys->types_ = std::make_unique<os::TaskTypeRegistry>(options.shared_types);
    if (auto s = robot::register_robot_task_types(*sys->types_, device_lookups(devices)); !s)
      return kernel::Error{"robot '" + spec.name + "': " + s.error()};
  } else {
    sys->types_ = std::make_unique<os::TaskTypeRegistry>();
    if (auto s = register_scenario_task_types(*sys->types_, devices, options.read_program); !s)
      return kernel::Error{"robot '" + spec.name + "': " + s.error()};
  }
  sys->node_ = std::make_unique<os::Node>(
      executor, os::NodeConfig{spec.name, options.seed, options.log_capacity, sys->types_.get()});
  os::Node& node = *sys->node_;

  // A device task over the device of the same name, with its declared ports.
  auto make_device = [&](std::string_view type, std::string_view device, std::vector<os::ParamAssignment> extra,
                         std::optional<kernel::Duration> period) -> kernel::Status {
    std::vector<os::ParamAssignment> params{{"device", std::string(device), 1}};
    for (auto& p : extra) params.push_back(std::move(p));
    os::TaskOptions o = sys->types_->find(type)->defaults;
    if (period) o.period = *period;
    o.ports = device_task_ports(device);
    if (auto r = node.create(type, std::string(device), params, o); !r)
      return kernel::Error{"robot '" + spec.name + "': " + std::string(device) + ": " + r.error()};
    return {};
  };
  // The optional device tasks only when used: each is a task woken every period. (A shell can
  // still make one later: `create sensor pose device=pose`.)
  auto used = [&](std::string_view device) {
    return std::any_of(spec.hooks.begin(), spec.hooks.end(),
                       [&](const HookSpec& h) { return h.from == device || h.to == device; }) ||
           std::any_of(spec.remote_hooks.begin(), spec.remote_hooks.end(),
                       [&](const RemoteHookSpec& h) { return h.from == device; }) ||
           std::find(options.named_device_tasks.begin(), options.named_device_tasks.end(), device) !=
               options.named_device_tasks.end();
  };
  // The watchdog: a controller that stops talking (suspended from the shell, deleted, faulted)
  // must not leave the robot driving on its last command.
  const auto timeout = options.control_period * 3 / 2;
  const std::vector<os::ParamAssignment> watchdog{
      {"timeout", std::to_string(std::chrono::duration_cast<std::chrono::microseconds>(timeout).count()) + "us", 1}};
  bool wants_wheels = true;
  if (options.make_device_tasks) {
    if (auto s = options.make_device_tasks(node); !s)
      return kernel::Error{"robot '" + spec.name + "': device tasks: " + s.error()};
  } else if (devices.module) {
    // A 3D module. The hinge has no watchdog: its servo holds the last target (a bent organism
    // that straightened on its own when a controller paused could push its neighbours).
    if (auto s = make_device("sensor", kIrTaskName, {}, std::nullopt); !s) return kernel::Error{s.error()};
    if (auto s = make_device("sensor", kHingeStateTaskName, {}, std::nullopt); !s) return kernel::Error{s.error()};
    if (auto s = make_device("actuator_sink", kHingeTaskName, {}, std::nullopt); !s) return kernel::Error{s.error()};
    wants_wheels = spec.module_kind.has_wheels;
    if (wants_wheels)
      if (auto s = make_device("actuator_sink", kWheelsTaskName, watchdog, options.control_period); !s)
        return kernel::Error{s.error()};
    for (const auto& c : spec.module_kind.connectors) {
      const std::string device = std::string(kConnectorTaskPrefix) + c.name;
      if (used(device))
        if (auto s = make_device("sensor", device, {}, std::nullopt); !s) return kernel::Error{s.error()};
    }
  } else {
    if (auto s = make_device("sensor", kIrTaskName, {}, std::nullopt); !s) return kernel::Error{s.error()};
    if (auto s = make_device("actuator_sink", kWheelsTaskName, watchdog, options.control_period); !s)
      return kernel::Error{s.error()};
    for (const std::string_view device : {kPoseTaskName, kGroundTaskName})
      if (used(device))
        if (auto s = make_device("sensor", device, {}, std::nullopt); !s) return kernel::Error{s.error()};
  }
  if (devices.radio != nullptr)
    if (auto r = devices.radio->add_to(node, devices.radio_index, std::string(kRadioTaskName)); !r)
      return kernel::Error{"robot '" + spec.name + "': radio: " + r.error()};
  for (const std::string_view device_task : {kIrTaskName, kWheelsTaskName})
    if ((device_task != kWheelsTaskName || wants_wheels) && !node.find(std::string(device_task)))
      return kernel::Error{"robot '" + spec.name + "': the device tasks made no task named '" +
                           std::string(device_task) + "'"};

  for (const TaskSpec& t : spec.tasks) {
    const os::TaskType* type = sys->types_->find(t.type);
    if (!type) return at(t.where, sys->types_->unknown_type_error(t.type));
    os::TaskOptions o = type->defaults;
    if (t.priority) o.priority = *t.priority;
    if (t.period) o.period = *t.period;
    if (t.queue_capacity) o.queue_capacity = *t.queue_capacity;
    o.autostart = t.autostart;
    if (auto r = node.create(t.type, t.name, t.params, o); !r)
      return at(t.where, "task '" + t.name + "': " + r.error());
  }
  for (const HookSpec& h : spec.hooks) {
    const auto from = node.find(h.from);
    const auto to = node.find(h.to);
    if (!from) return at(h.where, "hook: robot '" + spec.name + "' has no task '" + h.from + "'");
    if (!to) return at(h.where, "hook: robot '" + spec.name + "' has no task '" + h.to + "'");
    if (auto r = node.hook(*from, *to, h.options); !r) return at(h.where, "hook: " + r.error());
  }
  return sys;
}

RobotSystem* find_robot(const std::vector<std::unique_ptr<RobotSystem>>& robots, std::string_view name) {
  for (const auto& r : robots)
    if (r->name() == name) return r.get();
  return nullptr;
}

std::string first_cycle_error(const std::vector<std::unique_ptr<RobotSystem>>& robots) {
  for (const auto& r : robots)
    if (auto e = r->node().cycle_error(); !e.empty()) return e;
  return {};
}

RobotSystem::~RobotSystem() {
  if (node_) node_->clear();
}

}  // namespace symb::sim
