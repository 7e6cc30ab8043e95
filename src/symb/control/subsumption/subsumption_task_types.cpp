#include "symb/control/subsumption/subsumption_task_types.hpp"

#include <memory>
#include <string>

#include "symb/control/subsumption/subsumption_layers.hpp"
#include "symb/robot/ports.hpp"

namespace symb::control {

namespace {

using namespace std::chrono_literals;
using kernel::Error;
using kernel::Result;

// A layer type's parameters: its own options and the ones every layer shares.
template <class Own>
struct LayerParams : Own, LayerOptions {};

template <class Own>
void add_layer_params(os::ParamTable<LayerParams<Own>>& p) {
  using P = LayerParams<Own>;
  p.add("inhibit", &P::inhibit)
      .range(0, 63)
      .doc("a task whose output this layer blocks (through all its hooks) while active; empty: none")
      .live();
  p.add("inhibit_for", &P::inhibit_for).range(0.0, 3600.0).doc("how long each active step inhibits that task").live();
  p.add("speed_limit", &P::speed_limit).range(0.001, 1e6).doc("commands are clamped to +-this").live();
}

kernel::Status check_inhibit(const LayerOptions& o) {
  if (!o.inhibit.empty() && !os::is_valid_name(o.inhibit))
    return Error{"inhibit: '" + o.inhibit + "' is not a task name"};
  return {};
}

// Layers send wheel commands.
constexpr os::PortSpec kLayerOut{kLayerOutputPort, "wheels", robot::layout::kWheelCommand};

}  // namespace

kernel::Status register_subsumption_task_types(os::TaskTypeRegistry& registry, const ControlResources& /*resources*/) {
  // --- subsumption layers (docs/subsumption.md) ---------------------------------------------------
  {
    using P = LayerParams<WanderOptions>;
    os::ParamTable<P> p;
    p.add("speed", &P::speed).range(-500.0, 500.0).doc("forward wheel speed (Thymio units)").live();
    p.add("turn_max", &P::turn_max)
        .range(0.0, 500.0)
        .doc("turns drawn uniformly in +-this (wheel difference / 2)")
        .live();
    p.add("change_every", &P::change_every)
        .range(0.001, 3600.0)
        .doc("mean time between new turns (drawn in [0.5, 1.5] x this)")
        .live();
    add_layer_params(p);
    auto t = os::declare_task_type(
        "wander", "subsumption layer: forward with random turns at every tick; [left, right] out on port 0",
        std::move(p), [](const P& o) -> Result<std::unique_ptr<WanderLayer>> {
          if (auto st = check_inhibit(o); !st) return Error{st.error()};
          return std::make_unique<WanderLayer>(o, o);
        });
    t.defaults = os::TaskOptions{.priority = 1, .period = 30ms, .queue_capacity = 4};
    t.outputs = {kLayerOut};
    if (auto st = registry.add(std::move(t)); !st) return st;
  }
  {
    using P = LayerParams<AvoidOptions>;
    os::ParamTable<P> p;
    p.add("threshold", &P::threshold).range(0.0, 4505.0).doc("a front reading above this starts avoiding").live();
    p.add("turn", &P::turn).range(0.0, 500.0).doc("turning wheel speed").live();
    p.add("forward", &P::forward).range(-500.0, 500.0).doc("forward speed added while turning").live();
    p.add("hold", &P::hold).range(0.0, 3600.0).doc("keeps avoiding this long after the last close reading").live();
    add_layer_params(p);
    auto t = os::declare_task_type(
        "avoid",
        "subsumption layer: IR (7 values) in on port 0; turns away while a front sensor reads above threshold, "
        "silent otherwise",
        std::move(p), [](const P& o) -> Result<std::unique_ptr<AvoidLayer>> {
          if (auto st = check_inhibit(o); !st) return Error{st.error()};
          return std::make_unique<AvoidLayer>(o, o);
        });
    t.defaults = os::TaskOptions{.priority = 2, .period = kernel::Duration{0}, .queue_capacity = 4};
    t.inputs = {robot::kIrInput};
    t.outputs = {kLayerOut};
    if (auto st = registry.add(std::move(t)); !st) return st;
  }
  {
    using P = LayerParams<StopInZoneOptions>;
    os::ParamTable<P> p;
    p.add("zone_min", &P::zone_min).range(0.0, 1.0).doc("lowest floor reflectance counted as the zone").live();
    p.add("zone_max", &P::zone_max).range(0.0, 1.0).doc("highest floor reflectance counted as the zone").live();
    p.add("latch", &P::latch).doc("once in the zone, stop for good").live();
    p.add("after", &P::after)
        .range(0.0, 3600.0)
        .doc("stop only once both readings have been in the zone this long (drives further in)")
        .live();
    add_layer_params(p);
    auto t = os::declare_task_type(
        "stop_in_zone",
        "subsumption layer: ground readings [left, right] in on port 0; sends [0, 0] while both lie in "
        "[zone_min, zone_max]",
        std::move(p), [](const P& o) -> Result<std::unique_ptr<StopInZoneLayer>> {
          if (o.zone_min > o.zone_max) return Error{"zone_min must not exceed zone_max"};
          if (auto st = check_inhibit(o); !st) return Error{st.error()};
          return std::make_unique<StopInZoneLayer>(o, o);
        });
    t.defaults = os::TaskOptions{.priority = 3, .period = kernel::Duration{0}, .queue_capacity = 4};
    t.inputs = {{kLayerInputPort, "ground", robot::layout::kSensorVector}};
    t.outputs = {kLayerOut};
    if (auto st = registry.add(std::move(t)); !st) return st;
  }
  return {};
}

}  // namespace symb::control
