#include "symb/control/ahhs_task_types.hpp"

#include <memory>
#include <stdexcept>

#include "symb/control/ahhs/parser.hpp"
#include "symb/control/ahhs_compartment_task.hpp"
#include "symb/control/ahhs_task.hpp"

namespace symb::control {

namespace {

using namespace std::chrono_literals;
using os::ParamSpec;
using os::ParamType;

constexpr std::size_t kShownReference = 120;

std::string shown(const std::string& reference) {
  if (reference.size() <= kShownReference) return reference;
  return reference.substr(0, kShownReference) + "...";
}

// The network named by `network=REFERENCE` (read through read_program) or written inline in
// `description=TEXT` (statements separated by ';'); exactly one of the two.
ahhs::Network network_of(const os::ParamSet& p, const ControlResources& resources) {
  const std::string& reference = p.string("network");
  const std::string& inline_text = p.string("description");
  if (reference.empty() == inline_text.empty())
    throw std::invalid_argument(
        "give the network either by reference (network=FILE) or inline (description=\"compartments 1; ...\"), "
        "exactly one");
  if (!inline_text.empty()) {
    auto n = ahhs::parse_network(inline_text);
    if (!n) throw std::invalid_argument("description: " + n.error());
    return std::move(n).value();
  }
  if (!resources.read_program) throw std::invalid_argument("this node cannot read networks (no read_program)");
  auto text = resources.read_program(reference);
  if (!text) throw std::invalid_argument("network '" + shown(reference) + "': " + text.error());
  auto n = ahhs::parse_network(*text);
  if (!n) throw std::invalid_argument("network '" + shown(reference) + "': " + n.error());
  return std::move(n).value();
}

AhhsTaskOptions options_of(const os::ParamSet& p, bool sensors, bool actuators) {
  AhhsTaskOptions o;
  if (sensors) o.sensor_range = p.real("sensor_range");
  if (actuators) o.actuator_scale = p.real("actuator_scale");
  o.warn_interval = p.duration("warn_interval");
  return o;
}

const AhhsTaskOptions kDefaults;

ParamSpec network_param() {
  return {"network",     ParamType::kString,
          std::string(), 0.0,
          1024.0,        "the network description to run (a reference the node resolves, e.g. ahhs/two_hormone.ahhs)"};
}
ParamSpec description_param() {
  return {"description", ParamType::kString,
          std::string(), 0.0,
          65536.0,       "the network description inline, statements separated by ';' (instead of network=)"};
}
ParamSpec sensor_range_param() {
  return {"sensor_range",
          ParamType::kReal,
          kDefaults.sensor_range,
          1e-6,
          1e9,
          "a raw sensor value of this reads 1 (values are clamped to [0, 1])"};
}
ParamSpec actuator_scale_param() {
  return {"actuator_scale",
          ParamType::kReal,
          kDefaults.actuator_scale,
          0.001,
          500.0,
          "an actuator at 1 sends this (wheel units; at most 500)"};
}
ParamSpec warn_param() {
  return {"warn_interval",
          ParamType::kDuration,
          kDefaults.warn_interval,
          0.0,
          3600.0,
          "at most one warning of a kind per interval (counts say how many it stands for)"};
}

}  // namespace

kernel::Status register_ahhs_task_types(os::TaskTypeRegistry& registry, const ControlResources& resources) {
  auto shared = std::make_shared<const ControlResources>(resources);

  os::TaskType whole;
  whole.name = "ahhs";
  whole.doc =
      "a hormone controller (AHHS), the whole network in one task: sensor vectors in on port 0 (each steps the "
      "network once), actuators out on port 0 scaled to wheel units; probes hormones/c<k> and actuators";
  whole.params = {network_param(), description_param(), sensor_range_param(), actuator_scale_param(), warn_param()};
  whole.defaults.priority = 2;
  whole.defaults.queue_capacity = 4;
  whole.make = [shared](const os::ParamSet& p) -> std::unique_ptr<os::Task> {
    auto task = AhhsTask::create(network_of(p, *shared), options_of(p, true, true));
    if (!task) throw std::invalid_argument(task.error());
    return std::move(task).value();
  };
  if (auto st = registry.add(std::move(whole)); !st) return st;

  os::TaskType compartment;
  compartment.name = "ahhs_compartment";
  compartment.doc =
      "one compartment of a hormone controller (AHHS): sensor vectors in on port 0, neighbours' levels in and "
      "its own out on port 1 ([compartment id, h0..]), its actuators out on port 2 ([index, value, ...], for "
      "ahhs_mixer); probes hormones/c<k> and actuators";
  compartment.params = {network_param(),
                        description_param(),
                        {"compartment", ParamType::kInt, std::int64_t{0}, 0.0,
                         static_cast<double>(ahhs::kMaxCompartments - 1), "which compartment of the network this is"},
                        sensor_range_param(),
                        warn_param()};
  compartment.defaults.priority = 2;
  compartment.defaults.queue_capacity = 16;
  compartment.make = [shared](const os::ParamSet& p) -> std::unique_ptr<os::Task> {
    auto task = AhhsCompartmentTask::create(
        network_of(p, *shared), static_cast<std::uint32_t>(p.integer("compartment")), options_of(p, true, false));
    if (!task) throw std::invalid_argument(task.error());
    return std::move(task).value();
  };
  if (auto st = registry.add(std::move(compartment)); !st) return st;

  os::TaskType mixer;
  mixer.name = "ahhs_mixer";
  mixer.doc =
      "gathers [actuator index, value, ...] from ahhs_compartment tasks on port 2 and sends the whole actuator "
      "vector, scaled to wheel units, on port 0 once every actuator has its value";
  mixer.params = {{"actuators", ParamType::kInt, std::int64_t{2}, 1.0, static_cast<double>(ahhs::kMaxActuators),
                   "how many actuators the network drives"},
                  actuator_scale_param(),
                  warn_param()};
  mixer.defaults.priority = 2;
  mixer.defaults.queue_capacity = 16;
  mixer.make = [](const os::ParamSet& p) -> std::unique_ptr<os::Task> {
    auto task = AhhsMixerTask::create(static_cast<std::size_t>(p.integer("actuators")), options_of(p, false, true));
    if (!task) throw std::invalid_argument(task.error());
    return std::move(task).value();
  };
  return registry.add(std::move(mixer));
}

}  // namespace symb::control
