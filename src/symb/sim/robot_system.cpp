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

kernel::Status register_scenario_task_types(os::TaskTypeRegistry& registry, RobotDevices devices,
                                            ProgramReader read_program) {
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
  if (auto s = robot::register_robot_task_types(registry, std::move(lookups)); !s) return s;
  control::ControlResources resources;
  resources.read_program = std::move(read_program);
  if (auto st = control::register_control_task_types(registry, resources); !st) return st;
  return evo::register_evo_task_types(registry, resources);
}

kernel::Result<std::unique_ptr<RobotSystem>> RobotSystem::build(kernel::Executor& executor, const RobotSpec& spec,
                                                                RobotDevices devices, RobotSystemOptions options) {
  std::unique_ptr<RobotSystem> sys(new RobotSystem());
  sys->name_ = spec.name;
  sys->types_ = std::make_unique<os::TaskTypeRegistry>();
  if (auto s = register_scenario_task_types(*sys->types_, devices, options.read_program); !s)
    return kernel::Error{"robot '" + spec.name + "': " + s.error()};
  sys->node_ = std::make_unique<os::Node>(
      executor, os::NodeConfig{spec.name, options.seed, options.log_capacity, sys->types_.get()});
  os::Node& node = *sys->node_;

  if (options.make_device_tasks) {
    if (auto s = options.make_device_tasks(node); !s)
      return kernel::Error{"robot '" + spec.name + "': device tasks: " + s.error()};
  } else {
    const std::vector<os::ParamAssignment> ir_params{{"device", std::string(kIrTaskName), 1}};
    os::TaskOptions ir_options = sys->types_->find("sensor")->defaults;
    ir_options.ports = device_task_ports(kIrTaskName);
    if (auto r = node.create("sensor", std::string(kIrTaskName), ir_params, ir_options); !r)
      return kernel::Error{"robot '" + spec.name + "': ir: " + r.error()};
    // The watchdog: a controller that stops talking (suspended from the shell, deleted, faulted)
    // must not leave the robot driving on its last command.
    const auto timeout = options.control_period * 3 / 2;
    const std::vector<os::ParamAssignment> wheel_params{
        {"device", std::string(kWheelsTaskName), 1},
        {"timeout", std::to_string(std::chrono::duration_cast<std::chrono::microseconds>(timeout).count()) + "us", 1}};
    os::TaskOptions wheel_options = sys->types_->find("actuator_sink")->defaults;
    wheel_options.period = options.control_period;
    wheel_options.ports = device_task_ports(kWheelsTaskName);
    if (auto r = node.create("actuator_sink", std::string(kWheelsTaskName), wheel_params, wheel_options); !r)
      return kernel::Error{"robot '" + spec.name + "': wheels: " + r.error()};
    // Pose and ground only when used: each is a task woken every period. (A shell can still make
    // one later: `create sensor pose device=pose`.)
    for (const std::string_view device : {kPoseTaskName, kGroundTaskName}) {
      const bool used = std::any_of(spec.hooks.begin(), spec.hooks.end(),
                                    [&](const HookSpec& h) { return h.from == device || h.to == device; });
      if (!used) continue;
      const std::vector<os::ParamAssignment> params{{"device", std::string(device), 1}};
      os::TaskOptions device_options = sys->types_->find("sensor")->defaults;
      device_options.ports = device_task_ports(device);
      if (auto r = node.create("sensor", std::string(device), params, device_options); !r)
        return kernel::Error{"robot '" + spec.name + "': " + std::string(device) + ": " + r.error()};
    }
  }
  if (devices.radio != nullptr)
    if (auto r = devices.radio->add_to(node, devices.radio_index, std::string(kRadioTaskName)); !r)
      return kernel::Error{"robot '" + spec.name + "': radio: " + r.error()};
  for (const char* device_task : {kIrTaskName.data(), kWheelsTaskName.data()})
    if (!node.find(device_task))
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

RobotSystem::~RobotSystem() {
  if (node_) node_->clear();
}

}  // namespace symb::sim
