// Scenario files -> Scenario: a walk over the YAML tree that knows the scenario's schema, on the
// sim layer's YAML scaffold (yaml_document.hpp: bounds, located failures, keys checked against a
// schema, scalars read in range), which also keeps every exception inside this file.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <sstream>
#include <system_error>
#include <tuple>
#include <utility>

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include "symb/kernel/random_stream.hpp"
#include "symb/sim/scenario.hpp"
#include "symb/sim/yaml_document.hpp"

namespace symb::sim {
namespace {

using kernel::Error;

constexpr std::int64_t kMaxPriority = 1000;  // as the shell allows
constexpr std::int64_t kMaxQueue = 65536;
constexpr std::int64_t kMaxPort = 65535;
constexpr double kMaxArena = 5000.0;  // cm
constexpr double kMinArena = 2 * kStartClearance;
constexpr double kMinWallLength = 0.1;  // cm
constexpr double kMaxThickness = 50.0;
constexpr std::size_t kMaxTasksPerRobot = 256;
constexpr std::size_t kMaxHooksPerRobot = 1024;
constexpr std::size_t kMaxParamsPerTask = 64;
// After `count` expansion; a file can only make this many objects whatever its aliases say.
constexpr std::size_t kMaxTotalTasks = 100000;
constexpr std::size_t kMaxTotalHooks = 100000;
constexpr std::size_t kMaxTotalParams = 200000;
// Random starts are picked from a grid of at most about this many points.
constexpr double kMaxPlacementCandidates = 10000;
constexpr std::uint64_t kPlacementStream = 0x5ce7a810;

using yaml::Failure;
using yaml::Map;
using yaml::shown;
using yaml::Source;

bool is_scenario_name(std::string_view n) {
  if (n.empty() || n.size() > 63) return false;
  auto alpha = [](char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; };
  if (!alpha(n.front())) return false;
  return std::all_of(n.begin(), n.end(), [&](char c) { return alpha(c) || (c >= '0' && c <= '9') || c == '-'; });
}

std::string trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return std::string(s);
}

// Distance from (x, y) to the segment (x1, y1)-(x2, y2).
double segment_distance(double x, double y, double x1, double y1, double x2, double y2) {
  const double dx = x2 - x1, dy = y2 - y1;
  const double len2 = dx * dx + dy * dy;
  double t = len2 > 0 ? ((x - x1) * dx + (y - y1) * dy) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return std::hypot(x - (x1 + t * dx), y - (y1 + t * dy));
}

// The scenario's own kinds of value on top of the shared scalar reader.
class Reader : public yaml::Reader {
 public:
  explicit Reader(const Source& src) : yaml::Reader(src) {}

  std::string name(const YAML::Node& n, std::string_view what) const {
    std::string s = text(n, what);
    if (!is_scenario_name(s))
      src_.fail(n, std::string(what) + " '" + shown(s) +
                       "' is not a valid name: 1 to 63 letters, digits, '_' or '-', starting with a letter or '_'");
    return s;
  }

  std::string task_name(const YAML::Node& n, std::string_view what) const {
    std::string s = text(n, what);
    if (!os::is_valid_name(s))
      src_.fail(n, std::string(what) + " '" + shown(s) +
                       "' is not a valid task name: 1 to 63 letters, digits, '_', '.' or '-', starting with a "
                       "letter or '_'");
    return s;
  }

  kernel::Duration duration(const YAML::Node& n, std::string_view what, kernel::Duration lo,
                            kernel::Duration hi) const {
    const std::string s = text(n, what);
    auto d = os::parse_duration(s);
    if (!d) src_.fail(n, std::string(what) + ": " + d.error());
    if (*d < lo || *d > hi)
      src_.fail(n, std::string(what) + " must be between " + fmt_duration(lo) + " and " + fmt_duration(hi) + ", got " +
                       shown(s));
    return *d;
  }

  std::pair<double, double> point(const YAML::Node& n, std::string_view what, const WorldSpec& w) const {
    auto xy = list(n, what, 2);
    if (!n.IsSequence() || xy.size() != 2) src_.fail(n, std::string(what) + " must be a point [x, y]" + Map::got(n));
    return {number(xy[0], "x", 0, w.width), number(xy[1], "y", 0, w.height)};
  }

  static std::string fmt_duration(kernel::Duration d) { return os::format_param_value(os::ParamValue{d}); }
};

struct Parser {
  const Source& src;
  Reader rd;
  Scenario sc;
  std::size_t total_tasks = 0;
  std::size_t total_hooks = 0;
  std::size_t total_params = 0;

  explicit Parser(const Source& s) : src(s), rd(s) {}

  void top(const YAML::Node& root) {
    if (!root.IsDefined() || root.IsNull())
      src.fail(SourceLocation{src.file(), 1, 1}, "the scenario is empty: it needs at least name, world and robots");
    Map m(src, root, "the scenario", {"name", "description", "seed", "duration", "control_period", "world", "robots"});
    sc.name = rd.name(m.require("name"), "name");
    if (auto d = m.get("description"); d.IsDefined() && !d.IsNull()) sc.description = rd.text(d, "description");
    if (auto s = m.get("seed"); s.IsDefined()) sc.seed = rd.unsigned_integer(s, "seed");
    if (auto d = m.get("duration"); d.IsDefined())
      sc.duration = rd.duration(d, "duration", std::chrono::milliseconds(1), kMaxRunDuration);
    if (auto p = m.get("control_period"); p.IsDefined())
      sc.control_period = rd.duration(p, "control_period", std::chrono::milliseconds(1), std::chrono::seconds(1));
    world(m.require("world"));
    robots(m.require("robots"));
  }

  void world(const YAML::Node& n) {
    Map m(src, n, "world", {"arena", "wall_height", "walls", "zones", "radio"});
    Map arena(src, m.require("arena"), "arena", {"width", "height"});
    sc.world.width = rd.number(arena.require("width"), "arena width (cm)", kMinArena, kMaxArena);
    sc.world.height = rd.number(arena.require("height"), "arena height (cm)", kMinArena, kMaxArena);
    if (auto h = m.get("wall_height"); h.IsDefined()) sc.world.wall_height = rd.number(h, "wall_height (cm)", 1, 1000);
    for (const auto& w : rd.list(m.get("walls"), "walls", kMaxWalls)) sc.world.walls.push_back(wall(w));
    for (const auto& z : rd.list(m.get("zones"), "zones", kMaxZones)) sc.world.zones.push_back(zone(z));
    if (auto r = m.get("radio"); r.IsDefined()) sc.world.radio = radio(r);
  }

  // {range: CM, max_message_bytes: N}
  RadioSpec radio(const YAML::Node& n) {
    if (!n.IsMap()) src.fail(n, "radio is {range: CM, max_message_bytes: N}" + Map::got(n));
    Map m(src, n, "radio", {"range", "max_message_bytes"});
    RadioSpec r;
    const double diagonal = std::hypot(sc.world.width, sc.world.height);
    r.range = rd.number(m.require("range"), "radio range (cm)", 1, std::max(1.0, diagonal));
    if (auto b = m.get("max_message_bytes"); b.IsDefined())
      r.max_message_bytes = static_cast<std::size_t>(rd.integer(b, "radio max_message_bytes", 16, 1 << 20));
    return r;
  }

  // {rect: [x1, y1, x2, y2], ground: G, name: N} or {circle: [x, y, r], ground: G, name: N}.
  ZoneSpec zone(const YAML::Node& n) {
    ZoneSpec z;
    z.where = src.at(n);
    const WorldSpec& ws = sc.world;
    if (!n.IsMap())
      src.fail(n, "a zone is {rect: [x1, y1, x2, y2], ground: G} or {circle: [x, y, r], ground: G}" + Map::got(n));
    Map m(src, n, "a zone", {"rect", "circle", "ground", "name"});
    const YAML::Node rect = m.get("rect"), circle = m.get("circle");
    if (rect.IsDefined() == circle.IsDefined())
      src.fail(n, "a zone is either a rect: [x1, y1, x2, y2] or a circle: [x, y, r] (exactly one of them)");
    if (rect.IsDefined()) {
      const auto v = rd.list(rect, "rect", 4);
      if (!rect.IsSequence() || v.size() != 4) src.fail(rect, "rect is [x1, y1, x2, y2]" + Map::got(rect));
      z.shape = ZoneSpec::Shape::kRect;
      z.x1 = rd.number(v[0], "rect x1", 0, ws.width);
      z.y1 = rd.number(v[1], "rect y1", 0, ws.height);
      z.x2 = rd.number(v[2], "rect x2", 0, ws.width);
      z.y2 = rd.number(v[3], "rect y2", 0, ws.height);
      if (z.x2 <= z.x1 || z.y2 <= z.y1) src.fail(rect, "rect [x1, y1, x2, y2] needs x1 < x2 and y1 < y2");
    } else {
      const auto v = rd.list(circle, "circle", 3);
      if (!circle.IsSequence() || v.size() != 3) src.fail(circle, "circle is [x, y, r]" + Map::got(circle));
      z.shape = ZoneSpec::Shape::kCircle;
      z.cx = rd.number(v[0], "circle x", 0, ws.width);
      z.cy = rd.number(v[1], "circle y", 0, ws.height);
      z.radius = rd.number(v[2], "circle radius (cm)", 0.5, std::max(ws.width, ws.height));
    }
    z.ground = rd.number(m.require("ground"), "zone ground (reflectance)", 0, 1);
    if (auto nm = m.get("name"); nm.IsDefined()) z.name = rd.name(nm, "zone name");
    return z;
  }

  WallSpec wall(const YAML::Node& n) {
    WallSpec w;
    w.where = src.at(n);
    const WorldSpec& ws = sc.world;
    if (n.IsSequence()) {
      if (n.size() != 4)
        src.fail(n,
                 "a wall written as a list is [x1, y1, x2, y2]; this one has " + std::to_string(n.size()) + " numbers");
      const auto v = rd.list(n, "a wall", 4);
      w.x1 = rd.number(v[0], "wall x1", 0, ws.width);
      w.y1 = rd.number(v[1], "wall y1", 0, ws.height);
      w.x2 = rd.number(v[2], "wall x2", 0, ws.width);
      w.y2 = rd.number(v[3], "wall y2", 0, ws.height);
    } else if (n.IsMap()) {
      Map m(src, n, "a wall", {"from", "to", "thickness"});
      std::tie(w.x1, w.y1) = rd.point(m.require("from"), "wall 'from'", ws);
      std::tie(w.x2, w.y2) = rd.point(m.require("to"), "wall 'to'", ws);
      if (auto t = m.get("thickness"); t.IsDefined())
        w.thickness = rd.number(t, "wall thickness (cm)", 0.1, kMaxThickness);
    } else {
      src.fail(n, "a wall is [x1, y1, x2, y2] or {from: [x, y], to: [x, y], thickness: t}" + Map::got(n));
    }
    if (std::hypot(w.x2 - w.x1, w.y2 - w.y1) < kMinWallLength)
      src.fail(n, "this wall has (almost) zero length: its ends must be at least 1 mm apart");
    return w;
  }

  // One `robots` entry before `count` expansion.
  struct Entry {
    RobotSpec proto;
    std::size_t count = 1;
    bool counted = false;  // `count` was given: names get an index
    bool random = false;
    std::vector<Pose> starts;
    std::vector<SourceLocation> start_where;
    YAML::Node start_node;
  };

  void robots(const YAML::Node& n) {
    if (n.IsNull() || (n.IsSequence() && n.size() == 0)) src.fail(n, "robots is empty: a scenario needs a robot");
    auto items = rd.list(n, "robots", kMaxRobots);
    std::vector<Entry> entries;
    std::size_t total = 0;
    for (const auto& item : items) {
      entries.push_back(robot(item));
      total += entries.back().count;
      if (total > kMaxRobots) src.fail(item, "more than " + std::to_string(kMaxRobots) + " robots in one scenario");
      const Entry& e = entries.back();
      total_tasks += e.count * e.proto.tasks.size();
      total_hooks += e.count * e.proto.hooks.size();
      for (const auto& t : e.proto.tasks) total_params += e.count * t.params.size();
      if (total_tasks > kMaxTotalTasks || total_hooks > kMaxTotalHooks || total_params > kMaxTotalParams)
        src.fail(item, "too big: more than " + std::to_string(kMaxTotalTasks) + " tasks, " +
                           std::to_string(kMaxTotalHooks) + " hooks or " + std::to_string(kMaxTotalParams) +
                           " task parameters in one scenario, counting every copy `count` makes");
    }
    // Names, all expanded, unique across the file.
    std::map<std::string, SourceLocation, std::less<>> names;
    for (const auto& e : entries)
      for (std::size_t i = 0; i < e.count; ++i) {
        std::string nm = e.counted ? e.proto.name + std::to_string(i) : e.proto.name;
        if (nm.size() > 63) src.fail(e.proto.where, "robot name '" + shown(nm) + "' is longer than 63 characters");
        auto [it, fresh] = names.emplace(nm, e.proto.where);
        if (!fresh)
          src.fail(e.proto.where,
                   "robot name '" + nm + "' is already used (line " + std::to_string(it->second.line) + ")");
      }
    // Explicit starts first, in file order; random ones then fill the free space around them.
    std::vector<Pose> placed;
    for (const auto& e : entries)
      for (std::size_t i = 0; i < e.starts.size(); ++i) {
        check_start(e.starts[i], e.start_where[i], placed);
        placed.push_back(e.starts[i]);
      }
    std::vector<std::vector<Pose>> random_starts(entries.size());
    std::vector<std::pair<double, double>> free;
    kernel::RandomStream rng(sc.seed, kPlacementStream);
    std::size_t next = 0;
    bool have_free = false;
    for (std::size_t k = 0; k < entries.size(); ++k) {
      if (!entries[k].random) continue;
      if (!have_free) {
        free = free_cells(rng);
        have_free = true;
      }
      for (std::size_t i = 0; i < entries[k].count; ++i) {
        bool found = false;
        while (next < free.size() && !found) {
          const double x = free[next].first, y = free[next].second;
          ++next;
          constexpr double kApart2 = 4 * kStartClearance * kStartClearance;
          found = std::all_of(placed.begin(), placed.end(),
                              [&](const Pose& p) { return (p.x - x) * (p.x - x) + (p.y - y) * (p.y - y) >= kApart2; });
          if (found) {
            const Pose p{x, y, rng.uniform(-std::numbers::pi, std::numbers::pi)};
            placed.push_back(p);
            random_starts[k].push_back(p);
          }
        }
        if (!found)
          src.fail(entries[k].start_node, "no room for " + std::to_string(entries[k].count) + " robots here: only " +
                                              std::to_string(i) +
                                              " fit with 8 cm around each, clear of walls and other robots");
      }
    }
    for (std::size_t k = 0; k < entries.size(); ++k) {
      const Entry& e = entries[k];
      for (std::size_t i = 0; i < e.count; ++i) {
        RobotSpec r = e.proto;
        if (e.counted) r.name += std::to_string(i);
        r.start = e.random ? random_starts[k][i] : e.starts[i];
        sc.robots.push_back(std::move(r));
      }
    }
  }

  Entry robot(const YAML::Node& n) {
    Entry e;
    Map m(src, n, "a robot", {"name", "kind", "count", "start", "tasks", "hooks"});
    RobotSpec& r = e.proto;
    r.where = src.at(n);
    r.name = rd.name(m.require("name"), "robot name");
    if (auto k = m.get("kind"); k.IsDefined()) {
      const std::string kind = rd.text(k, "kind");
      if (kind != "thymio2") src.fail(k, "unknown robot kind '" + shown(kind) + "' (the only kind is thymio2)");
      r.kind = RobotKind::kThymio2;
    }
    if (auto c = m.get("count"); c.IsDefined()) {
      e.count = static_cast<std::size_t>(rd.integer(c, "count", 1, static_cast<std::int64_t>(kMaxRobots)));
      e.counted = true;
    }
    e.start_node = m.require("start");
    starts(e);
    for (const auto& t : rd.list(m.get("tasks"), "tasks", kMaxTasksPerRobot)) {
      TaskSpec ts = task(t);
      if (is_device_task_name(ts.name))
        src.fail(ts.where, "task name '" + ts.name + "' is taken: it names a device task (" + std::string(kIrTaskName) +
                               ", " + std::string(kWheelsTaskName) + ", " + std::string(kPoseTaskName) + ", " +
                               std::string(kGroundTaskName) + ", " + std::string(kRadioTaskName) + ")");
      for (const auto& other : r.tasks)
        if (other.name == ts.name)
          src.fail(ts.where, "robot '" + r.name + "' already has a task '" + ts.name + "' (line " +
                                 std::to_string(other.where.line) + ")");
      r.tasks.push_back(std::move(ts));
    }
    for (const auto& h : rd.list(m.get("hooks"), "hooks", kMaxHooksPerRobot)) hooks(h, r);
    return e;
  }

  void starts(Entry& e) {
    const YAML::Node& s = e.start_node;
    if (s.IsScalar()) {
      if (s.Scalar() != "random")
        src.fail(s, "start must be {x: X, y: Y, heading: DEGREES}, a list of those, or 'random'" + Map::got(s));
      e.random = true;
      return;
    }
    if (s.IsSequence()) {
      auto items = rd.list(s, "start", kMaxRobots);
      if (items.size() != e.count)
        src.fail(s, "start lists " + std::to_string(items.size()) + " poses for " + std::to_string(e.count) +
                        " robots (count)");
      for (const auto& p : items) {
        e.starts.push_back(pose(p));
        e.start_where.push_back(src.at(p));
      }
      return;
    }
    if (s.IsMap()) {
      if (e.count != 1)
        src.fail(s, std::to_string(e.count) + " robots cannot all start at one pose: give a list of " +
                        std::to_string(e.count) + " poses or 'random'");
      e.starts.push_back(pose(s));
      e.start_where.push_back(src.at(s));
      return;
    }
    src.fail(s, "start must be {x: X, y: Y, heading: DEGREES}, a list of those, or 'random'" + Map::got(s));
  }

  Pose pose(const YAML::Node& n) {
    Map m(src, n, "a start pose", {"x", "y", "heading"});
    Pose p;
    p.x = rd.number(m.require("x"), "start x (cm)", -kMaxArena, kMaxArena);
    p.y = rd.number(m.require("y"), "start y (cm)", -kMaxArena, kMaxArena);
    if (auto h = m.get("heading"); h.IsDefined())
      p.theta = rd.number(h, "heading (degrees)", -360, 360) * std::numbers::pi / 180.0;
    return p;
  }

  void check_start(const Pose& p, const SourceLocation& where, const std::vector<Pose>& placed) {
    const WorldSpec& w = sc.world;
    const std::string at = "(" + Reader::fmt(p.x) + ", " + Reader::fmt(p.y) + ")";
    if (p.x < 0 || p.y < 0 || p.x > w.width || p.y > w.height)
      src.fail(where, "start " + at + " is outside the arena (0..." + Reader::fmt(w.width) + ", 0..." +
                          Reader::fmt(w.height) + ")");
    const double side = std::min({p.x, p.y, w.width - p.x, w.height - p.y});
    if (side < kStartClearance)
      src.fail(where, "start " + at + " is " + Reader::fmt(side) +
                          " cm from the arena's side; a robot needs 8 cm around its start");
    for (const auto& wall : w.walls) {
      const double d = segment_distance(p.x, p.y, wall.x1, wall.y1, wall.x2, wall.y2) - wall.thickness / 2;
      if (d < kStartClearance)
        src.fail(where, "start " + at + " is " + (d <= 0 ? std::string("inside") : Reader::fmt(d) + " cm from") +
                            " the wall at line " + std::to_string(wall.where.line) +
                            "; a robot needs 8 cm around its start");
    }
    for (const auto& q : placed)
      if (std::hypot(p.x - q.x, p.y - q.y) < 2 * kStartClearance)
        src.fail(where, "start " + at + " is " + Reader::fmt(std::hypot(p.x - q.x, p.y - q.y)) +
                            " cm from another robot's start (" + Reader::fmt(q.x) + ", " + Reader::fmt(q.y) +
                            "); starts must be at least 16 cm apart");
  }

  // Grid points with 8 cm clear of every wall, in an order shuffled by the seed.
  std::vector<std::pair<double, double>> free_cells(kernel::RandomStream& rng) {
    const WorldSpec& w = sc.world;
    // Each wall as the box outside which no point can be too close, and the squared distance a
    // point must keep from its centre line. Copies of one wall (aliases make them cheaply) count
    // once; the box test keeps a maze's many short walls from costing a square root each.
    struct Keepout {
      double x1, y1, x2, y2, r2, lox, loy, hix, hiy;
      bool operator==(const Keepout&) const = default;
    };
    std::vector<Keepout> walls;
    for (const auto& s : w.walls) {
      const double r = kStartClearance + s.thickness / 2;
      const Keepout k{s.x1,
                      s.y1,
                      s.x2,
                      s.y2,
                      r * r,
                      std::min(s.x1, s.x2) - r,
                      std::min(s.y1, s.y2) - r,
                      std::max(s.x1, s.x2) + r,
                      std::max(s.y1, s.y2) + r};
      if (std::find(walls.begin(), walls.end(), k) == walls.end()) walls.push_back(k);
    }
    const double step = std::max(2.0, std::sqrt(w.width * w.height / kMaxPlacementCandidates));
    std::vector<std::pair<double, double>> out;
    for (double y = kStartClearance; y <= w.height - kStartClearance; y += step)
      for (double x = kStartClearance; x <= w.width - kStartClearance; x += step) {
        const bool clear = std::all_of(walls.begin(), walls.end(), [&](const Keepout& k) {
          if (x < k.lox || x > k.hix || y < k.loy || y > k.hiy) return true;
          const double d = segment_distance(x, y, k.x1, k.y1, k.x2, k.y2);
          return d * d >= k.r2;
        });
        if (clear) out.emplace_back(x, y);
      }
    for (std::size_t i = out.size(); i > 1; --i) std::swap(out[i - 1], out[rng.below(i)]);
    return out;
  }

  TaskSpec task(const YAML::Node& n) {
    Map m(src, n, "a task", {"name", "type", "params", "priority", "period", "queue", "autostart"});
    TaskSpec t;
    t.where = src.at(n);
    t.name = rd.task_name(m.require("name"), "task name");
    const YAML::Node type = m.require("type");
    t.type = rd.task_name(type, "task type");
    t.type_where = src.at(type);
    if (auto p = m.get("params"); p.IsDefined() && !p.IsNull()) {
      if (!p.IsMap()) src.fail(p, "params must be a mapping (name: value, ...)" + Map::got(p));
      if (p.size() > kMaxParamsPerTask)
        src.fail(p, "more than " + std::to_string(kMaxParamsPerTask) + " parameters for one task");
      for (const auto& kv : p) {
        const std::string name = rd.task_name(kv.first, "parameter name");
        for (std::size_t i = 0; i < t.params.size(); ++i)
          if (t.params[i].name == name)
            src.fail(kv.first, "parameter '" + name + "' given twice (first at line " +
                                   std::to_string(t.param_where[i].line) + ")");
        if (!kv.second.IsScalar())
          src.fail(kv.second.IsNull() ? kv.first : kv.second,
                   "parameter '" + name + "' needs a single value (a number, word or text)" + Map::got(kv.second));
        SourceLocation where = src.at(kv.first);
        t.params.push_back({name, kv.second.Scalar(), static_cast<std::size_t>(where.column)});
        t.param_where.push_back(std::move(where));
      }
    }
    if (auto v = m.get("priority"); v.IsDefined())
      t.priority = static_cast<int>(rd.integer(v, "priority", -kMaxPriority, kMaxPriority));
    if (auto v = m.get("period"); v.IsDefined())
      t.period = rd.duration(v, "period", kernel::Duration{0}, std::chrono::hours(1));
    if (auto v = m.get("queue"); v.IsDefined())
      t.queue_capacity = static_cast<std::size_t>(rd.integer(v, "queue", 1, kMaxQueue));
    if (auto v = m.get("autostart"); v.IsDefined()) t.autostart = rd.boolean(v, "autostart");
    return t;
  }

  // Every name a hook of robot `r` may use.
  bool has_task(const RobotSpec& r, std::string_view name) const {
    if (name == kRadioTaskName) return sc.world.radio.has_value();
    if (is_device_task_name(name)) return true;
    return std::any_of(r.tasks.begin(), r.tasks.end(), [&](const TaskSpec& t) { return t.name == name; });
  }

  void add_hook(RobotSpec& r, HookSpec h, const SourceLocation& to_where) {
    for (const std::string* end : {&h.from, &h.to})
      if (!has_task(r, *end)) {
        std::vector<std::string_view> names{kIrTaskName, kWheelsTaskName, kPoseTaskName, kGroundTaskName};
        for (const auto& t : r.tasks) names.push_back(t.name);
        if (sc.world.radio) names.push_back(kRadioTaskName);
        std::string msg = "robot '" + r.name + "' has no task '" + *end + "'";
        if (*end == kRadioTaskName)
          msg += ": robots have a radio only in a world that declares one (world: radio: {range: CM})";
        else if (auto hint = os::closest_name(*end, names); !hint.empty())
          msg += " (did you mean '" + hint + "'?)";
        src.fail(end == &h.from ? h.where : to_where, msg);
      }
    if (h.from == h.to) src.fail(h.where, "task '" + h.from + "' is hooked to itself");
    for (const auto& o : r.hooks)
      if (o.from == h.from && o.to == h.to && os::same_hook_key(o.options.port, h.options.port))
        src.fail(h.where, "hook " + h.from + " -> " + h.to + " is given twice (first at line " +
                              std::to_string(o.where.line) + ")");
    if (r.hooks.size() >= kMaxHooksPerRobot)
      src.fail(h.where, "more than " + std::to_string(kMaxHooksPerRobot) + " hooks for one robot");
    r.hooks.push_back(std::move(h));
  }

  void hooks(const YAML::Node& n, RobotSpec& r) {
    if (n.IsScalar()) {
      // "a -> b -> c": a chain of hooks with default options. Columns inside the text are exact
      // for a one-line scalar; a quoted one starts one column later.
      const std::string& s = n.Scalar();
      const int quote = n.Tag() == "!" ? 1 : 0;
      const bool one_line = s.find('\n') == std::string::npos;
      std::vector<std::pair<std::string, SourceLocation>> names;
      std::size_t from = 0;
      while (true) {
        const std::size_t arrow = s.find("->", from);
        const std::string part = s.substr(from, arrow == std::string::npos ? std::string::npos : arrow - from);
        std::size_t lead = 0;
        while (lead < part.size() && (part[lead] == ' ' || part[lead] == '\t')) ++lead;
        SourceLocation where =
            one_line ? src.at(n.Mark(), quote + static_cast<int>(from + std::min(lead, part.size()))) : src.at(n);
        const std::string name = trim(part);
        if (name.empty()) src.fail(where, "hook '" + shown(s) + "' is missing a task name; write 'sender -> receiver'");
        if (!os::is_valid_name(name))
          src.fail(where, "'" + shown(name) + "' in hook '" + shown(s) + "' is not a task name");
        names.emplace_back(name, where);
        if (arrow == std::string::npos) break;
        from = arrow + 2;
      }
      if (names.size() < 2) src.fail(n, "hook '" + shown(s) + "' needs an arrow: 'sender -> receiver'");
      for (std::size_t i = 0; i + 1 < names.size(); ++i) {
        HookSpec h;
        h.from = names[i].first;
        h.to = names[i + 1].first;
        h.where = names[i].second;
        add_hook(r, std::move(h), names[i + 1].second);
      }
      return;
    }
    if (!n.IsMap()) src.fail(n, "a hook is 'sender -> receiver' or {from: sender, to: receiver, ...}" + Map::got(n));
    Map m(src, n, "a hook", {"from", "to", "port", "priority", "policy", "suppress", "enabled"});
    HookSpec h;
    h.where = src.at(n);
    h.from = rd.task_name(m.require("from"), "hook 'from'");
    const YAML::Node to = m.require("to");
    h.to = rd.task_name(to, "hook 'to'");
    if (auto v = m.get("port"); v.IsDefined())
      h.options.port = static_cast<std::int32_t>(rd.integer(v, "port", 0, kMaxPort));
    if (auto v = m.get("priority"); v.IsDefined())
      h.options.priority = static_cast<int>(rd.integer(v, "hook priority", -kMaxPriority, kMaxPriority));
    if (auto v = m.get("policy"); v.IsDefined()) {
      const std::string p = rd.text(v, "policy");
      if (p == "keep_newest" || p == "keep-newest")
        h.options.policy = os::QueuePolicy::kKeepNewest;
      else if (p == "refuse")
        h.options.policy = os::QueuePolicy::kRefuse;
      else
        src.fail(v, "policy must be keep_newest or refuse, got '" + shown(p) + "'");
    }
    if (auto v = m.get("suppress"); v.IsDefined())
      h.options.suppress_window = rd.duration(v, "suppress", kernel::Duration{0}, std::chrono::hours(1));
    if (auto v = m.get("enabled"); v.IsDefined()) h.options.enabled = rd.boolean(v, "enabled");
    add_hook(r, std::move(h), src.at(to));
  }
};

}  // namespace

kernel::Result<Scenario> parse_scenario(std::string_view yaml_text, std::string_view file_name) {
  return yaml::parse_document<Scenario>(yaml_text, file_name, "a scenario", kMaxScenarioBytes, kMaxNesting,
                                        [&](const Source& src, const YAML::Node& root) {
                                          Parser p(src);
                                          p.sc.file = std::string(file_name);
                                          const std::string dir =
                                              std::filesystem::path(p.sc.file).parent_path().string();
                                          p.sc.base_dir = dir.empty() ? "." : dir;
                                          p.top(root);
                                          return std::move(p.sc);
                                        });
}

kernel::Result<Scenario> load_scenario(const std::string& path) {
  auto text = yaml::read_text_file(path, kMaxScenarioBytes, "scenario");
  if (!text) return Error{text.error()};
  auto sc = parse_scenario(*text, path);
  if (!sc) return sc;
  Scenario out = std::move(sc).value();
  const std::string dir = std::filesystem::path(path).parent_path().string();
  out.base_dir = dir.empty() ? "." : dir;
  return out;
}

}  // namespace symb::sim
