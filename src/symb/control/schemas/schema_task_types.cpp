#include "symb/control/schemas/schema_task_types.hpp"

#include <memory>
#include <string>

#include "symb/control/schemas/schema_tasks.hpp"
#include "symb/control/schemas/waypoints.hpp"
#include "symb/robot/ports.hpp"

namespace symb::control {

namespace {

using namespace std::chrono_literals;
using kernel::Error;
using kernel::Result;

constexpr double kMaxWaypointText = 8192;
constexpr double kMaxCoordinate = 1e6;

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

template <class P>
void add_gain(os::ParamTable<P>& p) {
  p.add("gain", &P::gain).range(0.0, 1000.0).doc("the schema's gain G: its vector's magnitude when fully on").live();
}

// Schemas send [vx, vy] into the sum, which sends wheel commands.
constexpr os::PortSpec kSchemaOut{0, "vector", robot::layout::kSchemaVector};
constexpr os::PortSpec kPoseIn{0, "pose", robot::layout::kPose};

}  // namespace

kernel::Status register_schema_task_types(os::TaskTypeRegistry& registry, const ControlResources& /*resources*/) {
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
    t.defaults = os::TaskOptions{.priority = 2, .period = kernel::Duration{0}, .queue_capacity = 4};
    t.inputs = {robot::kIrInput};
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
    t.defaults = os::TaskOptions{.priority = 2, .period = 100ms, .queue_capacity = 4};
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
    t.defaults = os::TaskOptions{.priority = 2, .period = 100ms, .queue_capacity = 4};
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
    t.defaults = os::TaskOptions{.priority = 2, .period = 100ms, .queue_capacity = 4};
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
    t.defaults = os::TaskOptions{.priority = 1, .period = 30ms, .queue_capacity = 16};
    t.inputs = {{0, "vectors", robot::layout::kSchemaVector}};
    t.outputs = {{0, "wheels", robot::layout::kWheelCommand}};
    if (auto st = registry.add(std::move(t)); !st) return st;
  }
  return {};
}

}  // namespace symb::control
