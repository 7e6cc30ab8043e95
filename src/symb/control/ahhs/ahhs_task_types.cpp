#include "symb/control/ahhs/ahhs_task_types.hpp"

#include <memory>

#include "symb/control/ahhs/ahhs_compartment_task.hpp"
#include "symb/control/ahhs/ahhs_task.hpp"
#include "symb/control/ahhs/parser.hpp"
#include "symb/robot/ports.hpp"

namespace symb::control {

namespace {

// The three types' parameters: the tasks' options and what the factories read.
struct AhhsParams : AhhsTaskOptions {
  std::string network;
  std::string description;
  std::int64_t compartment = 0;
  std::int64_t actuators = 2;
};

// The network named by `network=REFERENCE` (read through read_program) or written inline in
// `description=TEXT` (statements separated by ';'); exactly one of the two.
kernel::Result<ahhs::Network> network_of(const AhhsParams& p, const ControlResources& resources) {
  using kernel::Error;
  if (p.network.empty() == p.description.empty())
    return Error{
        "give the network either by reference (network=FILE) or inline (description=\"compartments 1; ...\"), "
        "exactly one"};
  if (!p.description.empty()) {
    auto n = ahhs::parse_network(p.description);
    if (!n) return Error{"description: " + n.error()};
    return n;
  }
  if (!resources.read_program) return Error{"this node cannot read networks (no read_program)"};
  auto text = resources.read_program(p.network);
  if (!text) return Error{"network '" + shown_reference(p.network) + "': " + text.error()};
  auto n = ahhs::parse_network(*text);
  if (!n) return Error{"network '" + shown_reference(p.network) + "': " + n.error()};
  return n;
}

void add_network(os::ParamTable<AhhsParams>& p) {
  p.add("network", &AhhsParams::network)
      .range(0, 1024)
      .doc("the network description to run (a reference the node resolves, e.g. ahhs/two_hormone.ahhs)");
  p.add("description", &AhhsParams::description)
      .range(0, 65536)
      .doc("the network description inline, statements separated by ';' (instead of network=)");
}
void add_sensor_range(os::ParamTable<AhhsParams>& p) {
  p.add("sensor_range", &AhhsParams::sensor_range)
      .range(1e-6, 1e9)
      .doc("a raw sensor value of this reads 1 (values are clamped to [0, 1])")
      .live();
}
void add_actuator_scale(os::ParamTable<AhhsParams>& p) {
  p.add("actuator_scale", &AhhsParams::actuator_scale)
      .range(0.001, 500.0)
      .doc("an actuator at 1 sends this (wheel units; at most 500)")
      .live();
}
void add_warn_interval(os::ParamTable<AhhsParams>& p) {
  p.add("warn_interval", &AhhsParams::warn_interval)
      .range(0.0, 3600.0)
      .doc("at most one warning of a kind per interval (counts say how many it stands for)")
      .live();
}

}  // namespace

kernel::Status register_ahhs_task_types(os::TaskTypeRegistry& registry, const ControlResources& resources) {
  using kernel::Error;
  using kernel::Result;
  auto shared = std::make_shared<const ControlResources>(resources);

  os::ParamTable<AhhsParams> wp;
  add_network(wp);
  add_sensor_range(wp);
  add_actuator_scale(wp);
  add_warn_interval(wp);
  auto whole = os::declare_task_type(
      "ahhs",
      "a hormone controller (AHHS), the whole network in one task: sensor vectors in on port 0 (each steps the "
      "network once), actuators out on port 0 scaled to wheel units; probes hormones/c<k> and actuators",
      std::move(wp), [shared](const AhhsParams& p) -> Result<std::unique_ptr<AhhsTask>> {
        auto network = network_of(p, *shared);
        if (!network) return Error{network.error()};
        return AhhsTask::create(std::move(network).value(), p);
      });
  whole.defaults.priority = 2;
  whole.defaults.queue_capacity = 4;
  whole.inputs = {{0, "sensors", robot::layout::kSensorVector}};
  whole.outputs = {{0, "actuators", robot::layout::kWheelCommand}};
  if (auto st = registry.add(std::move(whole)); !st) return st;

  os::ParamTable<AhhsParams> cp;
  add_network(cp);
  cp.add("compartment", &AhhsParams::compartment)
      .range(0.0, static_cast<double>(ahhs::kMaxCompartments - 1))
      .doc("which compartment of the network this is");
  add_sensor_range(cp);
  add_warn_interval(cp);
  auto compartment = os::declare_task_type(
      "ahhs_compartment",
      "one compartment of a hormone controller (AHHS): sensor vectors in on port 0, neighbours' levels in and "
      "its own out on port 1 ([compartment id, h0..]), its actuators out on port 2 ([index, value, ...], for "
      "ahhs_mixer); probes hormones/c<k> and actuators",
      std::move(cp), [shared](const AhhsParams& p) -> Result<std::unique_ptr<AhhsCompartmentTask>> {
        auto network = network_of(p, *shared);
        if (!network) return Error{network.error()};
        return AhhsCompartmentTask::create(std::move(network).value(), static_cast<std::uint32_t>(p.compartment), p);
      });
  compartment.defaults.priority = 2;
  compartment.defaults.queue_capacity = 16;
  compartment.inputs = {{0, "sensors", robot::layout::kSensorVector}};
  if (auto st = registry.add(std::move(compartment)); !st) return st;

  os::ParamTable<AhhsParams> mp;
  mp.add("actuators", &AhhsParams::actuators)
      .range(1.0, static_cast<double>(ahhs::kMaxActuators))
      .doc("how many actuators the network drives");
  add_actuator_scale(mp);
  add_warn_interval(mp);
  auto mixer = os::declare_task_type(
      "ahhs_mixer",
      "gathers [actuator index, value, ...] from ahhs_compartment tasks on port 2 and sends the whole actuator "
      "vector, scaled to wheel units, on port 0 once every actuator has its value",
      std::move(mp), [](const AhhsParams& p) -> Result<std::unique_ptr<AhhsMixerTask>> {
        return AhhsMixerTask::create(static_cast<std::size_t>(p.actuators), p);
      });
  mixer.defaults.priority = 2;
  mixer.defaults.queue_capacity = 16;
  mixer.outputs = {{0, "actuators", robot::layout::kWheelCommand}};
  return registry.add(std::move(mixer));
}

}  // namespace symb::control
