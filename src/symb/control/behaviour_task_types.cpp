#include "symb/control/behaviour_task_types.hpp"

#include <memory>
#include <stdexcept>
#include <string>

#include "symb/control/behaviour/waypoints.hpp"
#include "symb/control/schema_tasks.hpp"
#include "symb/control/subsumption_layers.hpp"

namespace symb::control {

namespace {

using namespace std::chrono_literals;
using os::ParamSpec;
using os::ParamType;

constexpr double kMaxWaypointText = 8192;
constexpr double kMaxCoordinate = 1e6;

std::vector<ParamSpec> layer_params(std::vector<ParamSpec> own) {
  const LayerOptions d;
  own.push_back({"inhibit", ParamType::kString, std::string(), 0.0, 63.0,
                 "a task whose output this layer blocks (through all its hooks) while active; empty: none"});
  own.push_back({"inhibit_for", ParamType::kDuration, kernel::Duration{0}, 0.0, 3600.0,
                 "how long each active step inhibits that task"});
  own.push_back({"speed_limit", ParamType::kReal, d.speed_limit, 0.001, 1e6, "commands are clamped to +-this"});
  return own;
}

LayerOptions layer_options(const os::ParamSet& p) {
  LayerOptions o;
  o.inhibit = p.string("inhibit");
  if (!o.inhibit.empty() && !os::is_valid_name(o.inhibit))
    throw std::invalid_argument("inhibit: '" + o.inhibit + "' is not a task name");
  o.inhibit_for = p.duration("inhibit_for");
  o.speed_limit = p.real("speed_limit");
  return o;
}

std::vector<behaviour::Point> waypoints(const os::ParamSet& p, const char* name) {
  auto w = behaviour::parse_waypoints(p.string(name));
  if (!w) throw std::invalid_argument(std::string(name) + ": " + w.error());
  return std::move(w).value();
}

os::TaskOptions defaults(int priority, kernel::Duration period, std::size_t queue) {
  os::TaskOptions o;
  o.priority = priority;
  o.period = period;
  o.queue_capacity = queue;
  return o;
}

ParamSpec gain_param(double d) {
  return {"gain", ParamType::kReal, d, 0.0, 1000.0, "the schema's gain G: its vector's magnitude when fully on"};
}

}  // namespace

kernel::Status register_behaviour_task_types(os::TaskTypeRegistry& registry, const ControlResources& /*resources*/) {
  // --- subsumption layers (docs/subsumption.md) ---------------------------------------------------
  {
    const WanderOptions d;
    os::TaskType t;
    t.name = "wander";
    t.doc = "subsumption layer: forward with random turns at every tick; [left, right] out on port 0";
    t.params = layer_params({
        {"speed", ParamType::kReal, d.speed, -500.0, 500.0, "forward wheel speed (Thymio units)"},
        {"turn_max", ParamType::kReal, d.turn_max, 0.0, 500.0,
         "turns drawn uniformly in +-this (wheel difference / 2)"},
        {"change_every", ParamType::kDuration, d.change_every, 0.001, 3600.0,
         "mean time between new turns (drawn in [0.5, 1.5] x this)"},
    });
    t.defaults = defaults(1, 30ms, 4);
    t.make = [](const os::ParamSet& p) -> std::unique_ptr<os::Task> {
      WanderOptions o{p.real("speed"), p.real("turn_max"), p.duration("change_every")};
      return std::make_unique<WanderLayer>(o, layer_options(p));
    };
    if (auto st = registry.add(std::move(t)); !st) return st;
  }
  {
    const AvoidOptions d;
    os::TaskType t;
    t.name = "avoid";
    t.doc =
        "subsumption layer: IR (7 values) in on port 0; turns away while a front sensor reads above threshold, "
        "silent otherwise";
    t.params = layer_params({
        {"threshold", ParamType::kReal, d.threshold, 0.0, 4505.0, "a front reading above this starts avoiding"},
        {"turn", ParamType::kReal, d.turn, 0.0, 500.0, "turning wheel speed"},
        {"forward", ParamType::kReal, d.forward, -500.0, 500.0, "forward speed added while turning"},
        {"hold", ParamType::kDuration, d.hold, 0.0, 3600.0, "keeps avoiding this long after the last close reading"},
    });
    t.defaults = defaults(2, kernel::Duration{0}, 4);
    t.make = [](const os::ParamSet& p) -> std::unique_ptr<os::Task> {
      AvoidOptions o{p.real("threshold"), p.real("turn"), p.real("forward"), p.duration("hold")};
      return std::make_unique<AvoidLayer>(o, layer_options(p));
    };
    if (auto st = registry.add(std::move(t)); !st) return st;
  }
  {
    const StopInZoneOptions d;
    os::TaskType t;
    t.name = "stop_in_zone";
    t.doc =
        "subsumption layer: ground readings [left, right] in on port 0; sends [0, 0] while both lie in "
        "[zone_min, zone_max]";
    t.params = layer_params({
        {"zone_min", ParamType::kReal, d.zone_min, 0.0, 1.0, "lowest floor reflectance counted as the zone"},
        {"zone_max", ParamType::kReal, d.zone_max, 0.0, 1.0, "highest floor reflectance counted as the zone"},
        {"latch", ParamType::kBool, d.latch, std::nullopt, std::nullopt, "once in the zone, stop for good"},
        {"after", ParamType::kDuration, d.after, 0.0, 3600.0,
         "stop only once both readings have been in the zone this long (drives further in)"},
    });
    t.defaults = defaults(3, kernel::Duration{0}, 4);
    t.make = [](const os::ParamSet& p) -> std::unique_ptr<os::Task> {
      StopInZoneOptions o{p.real("zone_min"), p.real("zone_max"), p.boolean("latch"), p.duration("after")};
      if (o.zone_min > o.zone_max) throw std::invalid_argument("zone_min must not exceed zone_max");
      return std::make_unique<StopInZoneLayer>(o, layer_options(p));
    };
    if (auto st = registry.add(std::move(t)); !st) return st;
  }

  // --- motor schemas (docs/motor_schemas.md) ------------------------------------------------------
  {
    const AvoidObstacleOptions d;
    os::TaskType t;
    t.name = "avoid_obstacle";
    t.doc =
        "motor schema: IR (7 values) in on port 0; [vx, vy] away from obstacles out on port 0 "
        "(G (S - d) / (S - R) per obstacle)";
    t.params = {
        gain_param(d.gain),
        {"sphere", ParamType::kReal, d.sphere, 0.1, 14.0, "S: sphere of influence, cm from the sensor"},
        {"safety", ParamType::kReal, d.safety, 0.0, 14.0, "R: safety margin, cm; closer counts as G * near_gain"},
        {"near_gain", ParamType::kReal, d.near_gain, 1.0, 1000.0, "Arkin's infinity, as a multiple of G"},
        {"combine", ParamType::kString, std::string("max"), 3.0, 3.0,
         "max (Balch: the strongest obstacle's magnitude) or sum (Arkin)"},
    };
    t.defaults = defaults(2, kernel::Duration{0}, 4);
    t.make = [](const os::ParamSet& p) -> std::unique_ptr<os::Task> {
      AvoidObstacleOptions o;
      o.gain = p.real("gain");
      o.sphere = p.real("sphere");
      o.safety = p.real("safety");
      o.near_gain = p.real("near_gain");
      const std::string& c = p.string("combine");
      if (c != "max" && c != "sum") throw std::invalid_argument("combine must be 'max' or 'sum', got '" + c + "'");
      o.use_max = c == "max";
      if (!(o.safety < o.sphere)) throw std::invalid_argument("safety (R) must be less than sphere (S)");
      return std::make_unique<AvoidObstacleSchema>(o);
    };
    if (auto st = registry.add(std::move(t)); !st) return st;
  }
  {
    const MoveToGoalOptions d;
    os::TaskType t;
    t.name = "move_to_goal";
    t.doc =
        "motor schema: pose [x, y, heading] in on port 0; [vx, vy] of magnitude G toward the next via "
        "waypoint, then the goal, out on port 0";
    t.params = {
        gain_param(d.gain),
        {"goal_x", ParamType::kReal, 0.0, -kMaxCoordinate, kMaxCoordinate, "the goal, cm"},
        {"goal_y", ParamType::kReal, 0.0, -kMaxCoordinate, kMaxCoordinate, "the goal, cm"},
        {"via", ParamType::kString, std::string(), 0.0, kMaxWaypointText,
         "waypoints on the way, \"x1,y1;x2,y2;...\" (cm); empty: straight to the goal"},
        {"reach", ParamType::kReal, d.reach, 0.1, 1000.0, "a via waypoint is passed within this (cm)"},
        {"arrive", ParamType::kReal, d.arrive, 0.0, 1000.0, "within this of the goal (cm) the schema rests"},
    };
    t.defaults = defaults(2, 100ms, 4);
    t.make = [](const os::ParamSet& p) -> std::unique_ptr<os::Task> {
      MoveToGoalOptions o;
      o.gain = p.real("gain");
      o.goal = {p.real("goal_x"), p.real("goal_y")};
      o.via = waypoints(p, "via");
      o.reach = p.real("reach");
      o.arrive = p.real("arrive");
      return std::make_unique<MoveToGoalSchema>(std::move(o));
    };
    if (auto st = registry.add(std::move(t)); !st) return st;
  }
  {
    const StayOnPathOptions d;
    os::TaskType t;
    t.name = "stay_on_path";
    t.doc = "motor schema: pose [x, y, heading] in on port 0; [vx, vy] toward the path's centre line out on port 0";
    t.params = {
        gain_param(d.gain),
        {"path", ParamType::kString, std::string(), 0.0, kMaxWaypointText,
         "the path, \"x1,y1;x2,y2;...\" (cm), at least 2 waypoints"},
        {"width", ParamType::kReal, d.width, 0.1, 1000.0, "path width (cm): full gain outside it"},
    };
    t.defaults = defaults(2, 100ms, 4);
    t.make = [](const os::ParamSet& p) -> std::unique_ptr<os::Task> {
      StayOnPathOptions o;
      o.gain = p.real("gain");
      o.path = waypoints(p, "path");
      if (o.path.size() < 2)
        throw std::invalid_argument("path: needs at least 2 waypoints, got " + std::to_string(o.path.size()));
      o.width = p.real("width");
      return std::make_unique<StayOnPathSchema>(std::move(o));
    };
    if (auto st = registry.add(std::move(t)); !st) return st;
  }
  {
    const NoiseOptions d;
    os::TaskType t;
    t.name = "noise";
    t.doc = "motor schema: [vx, vy] of magnitude G in a random direction, redrawn every persistence, out on port 0";
    t.params = {
        gain_param(d.gain),
        {"persistence", ParamType::kDuration, d.persistence, 0.001, 3600.0, "how long one direction is held"},
    };
    t.defaults = defaults(2, 100ms, 4);
    t.make = [](const os::ParamSet& p) -> std::unique_ptr<os::Task> {
      return std::make_unique<NoiseSchema>(NoiseOptions{p.real("gain"), p.duration("persistence")});
    };
    if (auto st = registry.add(std::move(t)); !st) return st;
  }
  {
    const SchemaSumOptions d;
    os::TaskType t;
    t.name = "schema_sum";
    t.doc =
        "motor schemas' sum: [vx, vy] from each schema in on port 0; at every tick the sum of the fresh ones "
        "as [left, right] out on port 0";
    t.params = {
        {"speed", ParamType::kReal, d.speed, 0.0, 500.0, "forward wheel speed for a sum of magnitude >= 1"},
        {"turn_speed", ParamType::kReal, d.turn_speed, 0.0, 500.0,
         "turning wheel speed for a sum 90 degrees or more off the heading"},
        {"max_age", ParamType::kDuration, d.max_age, 0.001, 3600.0, "older vectors no longer count"},
        {"min_magnitude", ParamType::kReal, d.min_magnitude, 0.0, 1000.0, "a smaller sum stops the wheels"},
        {"speed_limit", ParamType::kReal, d.speed_limit, 0.001, 1e6, "wheel speeds are clamped to +-this"},
    };
    t.defaults = defaults(1, 30ms, 16);
    t.make = [](const os::ParamSet& p) -> std::unique_ptr<os::Task> {
      SchemaSumOptions o{p.real("speed"), p.real("turn_speed"), p.duration("max_age"), p.real("min_magnitude"),
                         p.real("speed_limit")};
      return std::make_unique<SchemaSum>(o);
    };
    if (auto st = registry.add(std::move(t)); !st) return st;
  }
  return {};
}

}  // namespace symb::control
