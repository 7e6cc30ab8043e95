#include "symb/control/behaviour_task_types.hpp"

#include <memory>
#include <string>

#include "symb/control/behaviour/waypoints.hpp"
#include "symb/control/schema_tasks.hpp"
#include "symb/control/subsumption_layers.hpp"
#include "symb/robot/ports.hpp"

namespace symb::control {

namespace {

using namespace std::chrono_literals;
using kernel::Error;
using kernel::Result;

constexpr double kMaxWaypointText = 8192;
constexpr double kMaxCoordinate = 1e6;

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

// Waypoints "x1,y1;x2,y2;..." (cm), at least `min` of them.
os::ParamCodec<std::vector<behaviour::Point>> waypoints(std::string name, std::size_t min) {
  os::ParamCodec<std::vector<behaviour::Point>> c;
  c.type = os::ParamType::kString;
  c.parse = [name, min](const os::ParamValue& v) -> Result<std::vector<behaviour::Point>> {
    auto w = behaviour::parse_waypoints(std::get<std::string>(v));
    if (!w) return Error{name + ": " + w.error()};
    if (w->size() < min)
      return Error{name + ": needs at least " + std::to_string(min) + " waypoints, got " + std::to_string(w->size())};
    return w;
  };
  // Only the default (no waypoints) is ever formatted.
  c.format = [](const std::vector<behaviour::Point>&) -> os::ParamValue { return std::string(); };
  return c;
}

os::TaskOptions defaults(int priority, kernel::Duration period, std::size_t queue) {
  os::TaskOptions o;
  o.priority = priority;
  o.period = period;
  o.queue_capacity = queue;
  return o;
}

template <class P>
void add_gain(os::ParamTable<P>& p) {
  p.add("gain", &P::gain).range(0.0, 1000.0).doc("the schema's gain G: its vector's magnitude when fully on").live();
}

// Layers send wheel commands; schemas send [vx, vy] into the sum, which sends wheel commands.
constexpr os::PortSpec kLayerOut{kLayerOutputPort, "wheels", robot::layout::kWheelCommand};
constexpr os::PortSpec kSchemaOut{0, "vector", robot::layout::kSchemaVector};
constexpr os::PortSpec kIrIn{0, "ir", robot::layout::kSensorVector};
constexpr os::PortSpec kPoseIn{0, "pose", robot::layout::kPose};

}  // namespace

kernel::Status register_behaviour_task_types(os::TaskTypeRegistry& registry, const ControlResources& /*resources*/) {
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
    t.defaults = defaults(1, 30ms, 4);
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
    t.defaults = defaults(2, kernel::Duration{0}, 4);
    t.inputs = {kIrIn};
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
    t.defaults = defaults(3, kernel::Duration{0}, 4);
    t.inputs = {{kLayerInputPort, "ground", robot::layout::kSensorVector}};
    t.outputs = {kLayerOut};
    if (auto st = registry.add(std::move(t)); !st) return st;
  }

  // --- motor schemas (docs/motor_schemas.md) ------------------------------------------------------
  {
    using P = AvoidObstacleOptions;
    os::ParamTable<P> p;
    add_gain(p);
    p.add("sphere", &P::sphere).range(0.1, 14.0).doc("S: sphere of influence, cm from the sensor").live();
    p.add("safety", &P::safety).range(0.0, 14.0).doc("R: safety margin, cm; closer counts as G * near_gain").live();
    p.add("near_gain", &P::near_gain).range(1.0, 1000.0).doc("Arkin's infinity, as a multiple of G").live();
    p.add("combine", &P::use_max, os::choice<bool>("combine", {{"max", true}, {"sum", false}}))
        .range(3.0, 3.0)
        .doc("max (Balch: the strongest obstacle's magnitude) or sum (Arkin)")
        .live();
    auto t =
        os::declare_task_type("avoid_obstacle",
                              "motor schema: IR (7 values) in on port 0; [vx, vy] away from obstacles out on port 0 "
                              "(G (S - d) / (S - R) per obstacle)",
                              std::move(p), [](const P& o) -> Result<std::unique_ptr<AvoidObstacleSchema>> {
                                if (!(o.safety < o.sphere)) return Error{"safety (R) must be less than sphere (S)"};
                                return std::make_unique<AvoidObstacleSchema>(o);
                              });
    t.defaults = defaults(2, kernel::Duration{0}, 4);
    t.inputs = {kIrIn};
    t.outputs = {kSchemaOut};
    if (auto st = registry.add(std::move(t)); !st) return st;
  }
  {
    using P = MoveToGoalOptions;
    os::ParamTable<P> p;
    add_gain(p);
    p.add("goal_x", &P::goal, &behaviour::Point::x).range(-kMaxCoordinate, kMaxCoordinate).doc("the goal, cm").live();
    p.add("goal_y", &P::goal, &behaviour::Point::y).range(-kMaxCoordinate, kMaxCoordinate).doc("the goal, cm").live();
    p.add("via", &P::via, waypoints("via", 0))
        .range(0.0, kMaxWaypointText)
        .doc("waypoints on the way, \"x1,y1;x2,y2;...\" (cm); empty: straight to the goal")
        .live();
    p.add("reach", &P::reach).range(0.1, 1000.0).doc("a via waypoint is passed within this (cm)").live();
    p.add("arrive", &P::arrive).range(0.0, 1000.0).doc("within this of the goal (cm) the schema rests").live();
    auto t = os::declare_task_type(
        "move_to_goal",
        "motor schema: pose [x, y, heading] in on port 0; [vx, vy] of magnitude G toward the next via "
        "waypoint, then the goal, out on port 0",
        std::move(p), [](const P& o) { return std::make_unique<MoveToGoalSchema>(o); });
    t.defaults = defaults(2, 100ms, 4);
    t.inputs = {kPoseIn};
    t.outputs = {kSchemaOut};
    if (auto st = registry.add(std::move(t)); !st) return st;
  }
  {
    using P = StayOnPathOptions;
    os::ParamTable<P> p;
    add_gain(p);
    p.add("path", &P::path, waypoints("path", 2))
        .range(0.0, kMaxWaypointText)
        .doc("the path, \"x1,y1;x2,y2;...\" (cm), at least 2 waypoints")
        .live();
    p.add("width", &P::width).range(0.1, 1000.0).doc("path width (cm): full gain outside it").live();
    auto t = os::declare_task_type(
        "stay_on_path",
        "motor schema: pose [x, y, heading] in on port 0; [vx, vy] toward the path's centre line out on port 0",
        std::move(p), [](const P& o) { return std::make_unique<StayOnPathSchema>(o); });
    t.defaults = defaults(2, 100ms, 4);
    t.inputs = {kPoseIn};
    t.outputs = {kSchemaOut};
    if (auto st = registry.add(std::move(t)); !st) return st;
  }
  {
    using P = NoiseOptions;
    os::ParamTable<P> p;
    add_gain(p);
    p.add("persistence", &P::persistence).range(0.001, 3600.0).doc("how long one direction is held").live();
    auto t = os::declare_task_type(
        "noise",
        "motor schema: [vx, vy] of magnitude G in a random direction, redrawn every persistence, out on port 0",
        std::move(p), [](const P& o) { return std::make_unique<NoiseSchema>(o); });
    t.defaults = defaults(2, 100ms, 4);
    t.outputs = {kSchemaOut};
    if (auto st = registry.add(std::move(t)); !st) return st;
  }
  {
    using P = SchemaSumOptions;
    os::ParamTable<P> p;
    p.add("speed", &P::speed).range(0.0, 500.0).doc("forward wheel speed for a sum of magnitude >= 1").live();
    p.add("turn_speed", &P::turn_speed)
        .range(0.0, 500.0)
        .doc("turning wheel speed for a sum 90 degrees or more off the heading")
        .live();
    p.add("max_age", &P::max_age).range(0.001, 3600.0).doc("older vectors no longer count").live();
    p.add("min_magnitude", &P::min_magnitude).range(0.0, 1000.0).doc("a smaller sum stops the wheels").live();
    p.add("speed_limit", &P::speed_limit).range(0.001, 1e6).doc("wheel speeds are clamped to +-this").live();
    auto t = os::declare_task_type(
        "schema_sum",
        "motor schemas' sum: [vx, vy] from each schema in on port 0; at every tick the sum of the fresh ones "
        "as [left, right] out on port 0",
        std::move(p), [](const P& o) { return std::make_unique<SchemaSum>(o); });
    t.defaults = defaults(1, 30ms, 16);
    t.inputs = {{0, "vectors", robot::layout::kSchemaVector}};
    t.outputs = {{0, "wheels", robot::layout::kWheelCommand}};
    if (auto st = registry.add(std::move(t)); !st) return st;
  }
  return {};
}

}  // namespace symb::control
