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
#include <unordered_map>
#include <utility>
#include <vector>

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include "symb/kernel/random_stream.hpp"
#include "symb/shell/command_line.hpp"
#include "symb/shell/shell.hpp"
#include "symb/sim/mujoco/module_kind_file.hpp"
#include "symb/sim/mujoco/mujoco_world.hpp"
#include "symb/sim/scenario.hpp"
#include "symb/sim/yaml_document.hpp"

namespace symb::sim {
namespace {

using kernel::Error;

constexpr std::int64_t kMaxPriority = 1000;  // as the shell allows
constexpr std::int64_t kMaxQueue = 65536;
constexpr std::int64_t kMaxPort = 65535;
constexpr double kMaxArena = 10000.0;  // cm: 20,000 robots at 4,000 cm2 each need 90 m square
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
// Random starts are picked from a grid of at most about this many points, or four per random
// robot when there are more than a quarter of that.
constexpr double kMaxPlacementCandidates = 10000;
constexpr std::uint64_t kPlacementStream = 0x5ce7a810;
constexpr double kCm = 0.01;  // m: the file's unit in the world's
// A bus a CAN controller could run (10 kbit/s) up to a fast serial bus (100 Mbit/s).
constexpr std::int64_t kMinBusBandwidth = 10'000;
constexpr std::int64_t kMaxBusBandwidth = 100'000'000;
// Modules of one organism may touch; two faces may not reach into each other by more than this.
constexpr double kModuleOverlapSlack = 0.001;  // m

// The keys only one kind of world has: a located error names the other's.
constexpr std::string_view k2dWorldKeys[] = {"arena", "wall_height", "walls", "zones", "radio"};
constexpr std::string_view k3dWorldKeys[] = {"docked", "bus", "battery"};

using yaml::Failure;
using yaml::Map;
using yaml::shown;
using yaml::Source;

// Robot starts already placed, bucketed in square cells as wide as two starts must be apart, so
// checking a new start looks at the 3 x 3 cells around it instead of at every robot: placing
// 10,000 robots costs as much per robot as placing 10.
class StartGrid {
 public:
  static constexpr double kApart = 2 * kStartClearance;

  void add(const Pose& p) {
    cells_[key(p.x, p.y, 0, 0)].push_back(poses_.size());
    poses_.push_back(p);
  }
  // The earliest placed start q within kApart of (x, y) for which too_near(q) holds, or null.
  template <class TooNear>
  const Pose* first_near(double x, double y, TooNear too_near) const {
    std::size_t first = poses_.size();
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const auto it = cells_.find(key(x, y, dx, dy));
        if (it == cells_.end()) continue;
        for (const std::size_t i : it->second) {
          const Pose& q = poses_[i];
          if (i < first && too_near(q)) first = i;
        }
      }
    return first < poses_.size() ? &poses_[first] : nullptr;
  }

 private:
  // Starts lie within the arena (at most kMaxArena across), so a cell index fits 32 bits.
  static std::uint64_t key(double x, double y, int dx, int dy) {
    const auto cx = static_cast<std::uint32_t>(static_cast<std::int64_t>(std::floor(x / kApart)) + dx);
    const auto cy = static_cast<std::uint32_t>(static_cast<std::int64_t>(std::floor(y / kApart)) + dy);
    return (std::uint64_t{cy} << 32) | cx;
  }
  std::unordered_map<std::uint64_t, std::vector<std::size_t>> cells_;
  std::vector<Pose> poses_;
};

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
  ModuleKindReader read_kind;
  std::map<std::string, mujoco::ModuleKind, std::less<>> kinds;  // by the name as written
  YAML::Node docked_node;                                        // world.docked, read once the robots are known
  // Per robot (expanded): the start the file gives, if any, and where.
  std::vector<std::optional<Pose>> given_start;
  std::vector<SourceLocation> given_where;
  std::map<std::string, std::size_t, std::less<>> robot_indices;  // expanded names, once all are known

  Parser(const Source& s, ModuleKindReader reader) : src(s), rd(s), read_kind(std::move(reader)) {}

  bool in_3d() const { return sc.world_kind == WorldKind::kMujoco; }

  void top(const YAML::Node& root) {
    if (!root.IsDefined() || root.IsNull())
      src.fail(SourceLocation{src.file(), 1, 1}, "the scenario is empty: it needs at least name, world and robots");
    Map m(src, root, "the scenario",
          {"name", "description", "seed", "duration", "control_period", "world", "robots", "events", "plugins"});
    sc.name = rd.name(m.require("name"), "name");
    if (auto d = m.get("description"); d.IsDefined() && !d.IsNull()) sc.description = rd.text(d, "description");
    if (auto s = m.get("seed"); s.IsDefined()) sc.seed = rd.unsigned_integer(s, "seed");
    if (auto d = m.get("duration"); d.IsDefined())
      sc.duration = rd.duration(d, "duration", std::chrono::milliseconds(1), kMaxRunDuration);
    if (auto p = m.get("control_period"); p.IsDefined())
      sc.control_period = rd.duration(p, "control_period", std::chrono::milliseconds(1), std::chrono::seconds(1));
    world(m.require("world"));
    robots(m.require("robots"));
    if (in_3d()) {
      docked();
      place_modules();
    }
    resolve_remote_hooks();
    events(m.get("events"));
    plugins(m.get("plugins"));
  }

  void plugins(const YAML::Node& n) {
    if (!n.IsDefined() || n.IsNull()) return;
    for (const auto& item : rd.list(n, "plugins", kMaxPlugins)) {
      std::filesystem::path p{rd.text(item, "plugin path")};
      if (p.is_relative()) p = std::filesystem::path(sc.base_dir) / p;
      sc.plugins.push_back({p.lexically_normal().string(), src.at(item)});
    }
  }

  void world(const YAML::Node& n) {
    Map m(src, n, "world",
          {"kind", "engine", "arena", "wall_height", "walls", "zones", "radio", "docked", "bus", "battery"});
    if (auto k = m.get("kind"); k.IsDefined()) {
      const std::string kind = rd.text(k, "world kind");
      if (kind == "mujoco")
        sc.world_kind = WorldKind::kMujoco;
      else if (kind != "enki")
        src.fail(k, "unknown world kind '" + shown(kind) +
                        "' (enki: the 2D arena, the default; mujoco: the 3D world of modules)");
    }
    if (auto e = m.get("engine"); e.IsDefined()) {
      if (in_3d())
        src.fail(e,
                 "'engine' chooses the physics of a 2D world (enki or box2d); a 3D world (kind: mujoco) runs on "
                 "MuJoCo");
      const std::string engine = rd.text(e, "world engine");
      if (engine == "box2d")
        sc.world.engine = Engine2d::kBox2d;
      else if (engine != "enki")
        src.fail(e, "unknown world engine '" + shown(engine) +
                        "' (enki: the reference 2D simulator, the default; box2d: for swarms of thousands)");
    }
    if (in_3d()) {
      for (const std::string_view key : k2dWorldKeys)
        if (m.has(key))
          src.fail(m.get(key), "'" + std::string(key) +
                                   "' belongs to a 2D world: a 3D world (kind: mujoco) is an open floor without "
                                   "arena, walls, zones or radio");
      docked_node = m.get("docked");
      if (auto b = m.get("bus"); b.IsDefined()) sc.organism.bus = bus(b);
      if (auto b = m.get("battery"); b.IsDefined()) sc.organism.battery = battery(b);
      return;
    }
    for (const std::string_view key : k3dWorldKeys)
      if (m.has(key))
        src.fail(m.get(key), "'" + std::string(key) + "' belongs to a 3D world: add kind: mujoco to the world");
    Map arena(src, m.require("arena"), "arena", {"width", "height"});
    sc.world.width = rd.number(arena.require("width"), "arena width (cm)", kMinArena, kMaxArena);
    sc.world.height = rd.number(arena.require("height"), "arena height (cm)", kMinArena, kMaxArena);
    if (auto h = m.get("wall_height"); h.IsDefined()) sc.world.wall_height = rd.number(h, "wall_height (cm)", 1, 1000);
    for (const auto& w : rd.list(m.get("walls"), "walls", kMaxWalls)) sc.world.walls.push_back(wall(w));
    for (const auto& z : rd.list(m.get("zones"), "zones", kMaxZones)) sc.world.zones.push_back(zone(z));
    if (auto r = m.get("radio"); r.IsDefined()) sc.world.radio = radio(r);
  }

  // {bandwidth: BITS_PER_S, latency: DURATION}
  BusSpec bus(const YAML::Node& n) {
    if (!n.IsMap()) src.fail(n, "bus is {bandwidth: BITS_PER_SECOND, latency: DURATION}" + Map::got(n));
    Map m(src, n, "bus", {"bandwidth", "latency"});
    BusSpec b;
    b.where = src.at(n);
    if (auto v = m.get("bandwidth"); v.IsDefined())
      b.bandwidth =
          static_cast<std::uint64_t>(rd.integer(v, "bus bandwidth (bit/s)", kMinBusBandwidth, kMaxBusBandwidth));
    if (auto v = m.get("latency"); v.IsDefined())
      b.latency = rd.duration(v, "bus latency", kernel::Duration{0}, std::chrono::seconds(1));
    return b;
  }

  // {capacity: JOULES, share: BOOL}
  BatterySpec battery(const YAML::Node& n) {
    if (!n.IsMap()) src.fail(n, "battery is {capacity: JOULES, share: true|false}" + Map::got(n));
    Map m(src, n, "battery", {"capacity", "share"});
    BatterySpec b;
    b.where = src.at(n);
    if (auto v = m.get("capacity"); v.IsDefined()) b.capacity = rd.number(v, "battery capacity (J)", 1, 1e7);
    if (auto v = m.get("share"); v.IsDefined()) b.share = rd.boolean(v, "battery share");
    return b;
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
      total_hooks += e.count * (e.proto.hooks.size() + e.proto.remote_hooks.size());
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
    if (in_3d()) {
      // No arena to place in: starts as given (checked with the docks, place_modules).
      for (const auto& e : entries)
        for (std::size_t i = 0; i < e.count; ++i) {
          RobotSpec r = e.proto;
          if (e.counted) r.name += std::to_string(i);
          std::optional<Pose> start;
          SourceLocation where = e.proto.where;
          if (i < e.starts.size()) {
            start = e.starts[i];
            where = e.start_where[i];
          }
          given_start.push_back(start);
          given_where.push_back(std::move(where));
          sc.robots.push_back(std::move(r));
        }
      return;
    }
    // Explicit starts first, in file order; random ones then fill the free space around them.
    StartGrid placed;
    std::size_t random_total = 0;
    for (const auto& e : entries) {
      for (std::size_t i = 0; i < e.starts.size(); ++i) {
        check_start(e.starts[i], e.start_where[i], placed);
        placed.add(e.starts[i]);
      }
      if (e.random) random_total += e.count;
    }
    std::vector<std::vector<Pose>> random_starts(entries.size());
    std::vector<std::pair<double, double>> free;
    kernel::RandomStream rng(sc.seed, kPlacementStream);
    std::size_t next = 0;
    bool have_free = false;
    for (std::size_t k = 0; k < entries.size(); ++k) {
      if (!entries[k].random) continue;
      if (!have_free) {
        free = free_cells(rng, std::max(kMaxPlacementCandidates, 4.0 * static_cast<double>(random_total)));
        have_free = true;
      }
      for (std::size_t i = 0; i < entries[k].count; ++i) {
        bool found = false;
        while (next < free.size() && !found) {
          const double x = free[next].first, y = free[next].second;
          ++next;
          constexpr double kApart2 = 4 * kStartClearance * kStartClearance;
          found = placed.first_near(x, y, [&](const Pose& q) {
            return (q.x - x) * (q.x - x) + (q.y - y) * (q.y - y) < kApart2;
          }) == nullptr;
          if (found) {
            const Pose p{x, y, rng.uniform(-std::numbers::pi, std::numbers::pi)};
            placed.add(p);
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
    Map m(src, n, "a robot", {"name", "kind", "module", "count", "start", "tasks", "hooks"});
    RobotSpec& r = e.proto;
    r.where = src.at(n);
    const YAML::Node name_node = m.require("name");
    r.name = rd.name(name_node, "robot name");
    if (in_3d()) {
      if (r.name.find('-') != std::string::npos)
        src.fail(name_node, "module name '" + r.name +
                                "' has a '-': in a 3D world a name is letters, digits and '_' "
                                "(the world names its bodies after it)");
      if (auto k = m.get("kind"); k.IsDefined())
        src.fail(k,
                 "'kind' names a 2D robot; in a 3D world a robot names its module kind file: "
                 "module: modules/cube.yaml");
      const YAML::Node mod = m.require("module");
      r.module = rd.text(mod, "module");
      r.module_where = src.at(mod);
      r.module_kind = module_kind(mod, r.module);
    } else if (auto mod = m.get("module"); mod.IsDefined()) {
      src.fail(mod, "'module' names a 3D module kind: only in a 3D world (world: {kind: mujoco})");
    }
    if (auto k = m.get("kind"); k.IsDefined()) {
      const std::string kind = rd.text(k, "kind");
      if (kind != "thymio2") src.fail(k, "unknown robot kind '" + shown(kind) + "' (the only kind is thymio2)");
      r.kind = RobotKind::kThymio2;
    }
    if (auto c = m.get("count"); c.IsDefined()) {
      e.count = static_cast<std::size_t>(rd.integer(c, "count", 1, static_cast<std::int64_t>(kMaxRobots)));
      e.counted = true;
    }
    e.start_node = in_3d() ? m.get("start") : m.require("start");
    if (e.start_node.IsDefined()) starts(e);
    for (const auto& t : rd.list(m.get("tasks"), "tasks", kMaxTasksPerRobot)) {
      TaskSpec ts = task(t);
      if (is_device_task_name(ts.name))
        src.fail(ts.where, "task name '" + ts.name +
                               "' is taken: it names a device task (ir, wheels, pose, ground, radio, hinge, "
                               "hinge_state, connector_*)");
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
      if (in_3d())
        src.fail(s,
                 "a 3D world has no arena to place modules at random: give {x: X, y: Y, heading: DEGREES}, "
                 "or dock the module to one that has a start (world.docked)");
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
      // In 3D one pose for N modules places the first; world.docked places the others.
      if (e.count != 1 && !in_3d())
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

  void check_start(const Pose& p, const SourceLocation& where, const StartGrid& placed) {
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
    if (const Pose* q = placed.first_near(
            p.x, p.y, [&](const Pose& o) { return std::hypot(p.x - o.x, p.y - o.y) < 2 * kStartClearance; }))
      src.fail(where, "start " + at + " is " + Reader::fmt(std::hypot(p.x - q->x, p.y - q->y)) +
                          " cm from another robot's start (" + Reader::fmt(q->x) + ", " + Reader::fmt(q->y) +
                          "); starts must be at least 16 cm apart");
  }

  // Grid points with 8 cm clear of every wall, in an order shuffled by the seed.
  std::vector<std::pair<double, double>> free_cells(kernel::RandomStream& rng, double candidates) {
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
    const double step = std::max(2.0, std::sqrt(w.width * w.height / candidates));
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

  // The device tasks robot `r` has in this world.
  std::vector<std::string> device_tasks(const RobotSpec& r) const {
    if (!in_3d()) {
      std::vector<std::string> names{std::string(kIrTaskName), std::string(kWheelsTaskName), std::string(kPoseTaskName),
                                     std::string(kGroundTaskName)};
      if (sc.world.radio) names.emplace_back(kRadioTaskName);
      return names;
    }
    std::vector<std::string> names{std::string(kIrTaskName), std::string(kHingeStateTaskName),
                                   std::string(kHingeTaskName)};
    if (r.module_kind.has_wheels) names.emplace_back(kWheelsTaskName);
    for (const auto& c : r.module_kind.connectors) names.push_back(std::string(kConnectorTaskPrefix) + c.name);
    return names;
  }

  // Every name a hook of robot `r` may use.
  bool has_task(const RobotSpec& r, std::string_view name) const {
    if (is_device_task_name(name)) {
      const auto devices = device_tasks(r);
      return std::find(devices.begin(), devices.end(), name) != devices.end();
    }
    return std::any_of(r.tasks.begin(), r.tasks.end(), [&](const TaskSpec& t) { return t.name == name; });
  }

  [[noreturn]] void no_task(const RobotSpec& r, const std::string& name, const SourceLocation& where) const {
    const auto devices = device_tasks(r);
    // The radio last, after the robot's own tasks: the order the hint breaks ties in.
    std::vector<std::string_view> names;
    for (const auto& d : devices)
      if (d != kRadioTaskName) names.push_back(d);
    for (const auto& t : r.tasks) names.push_back(t.name);
    if (!in_3d() && sc.world.radio) names.push_back(kRadioTaskName);
    std::string msg = "robot '" + r.name + "' has no task '" + name + "'";
    if (name == kRadioTaskName && !in_3d())
      msg += ": robots have a radio only in a world that declares one (world: radio: {range: CM})";
    else if (name == kWheelsTaskName && in_3d())
      msg += ": its module kind '" + r.module_kind.name + "' has no wheels";
    else if (auto hint = os::closest_name(name, names); !hint.empty())
      msg += " (did you mean '" + hint + "'?)";
    src.fail(where, msg);
  }

  void add_hook(RobotSpec& r, HookSpec h, const SourceLocation& to_where) {
    for (const std::string* end : {&h.from, &h.to})
      if (!has_task(r, *end)) no_task(r, *end, end == &h.from ? h.where : to_where);
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
        if (name.find('/') != std::string::npos)
          src.fail(where, "'" + shown(name) + "' names another robot's task: write that hook in the long form, " +
                              "{from: TASK, to: ROBOT/TASK}");
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
    const bool remote = to.IsScalar() && to.Scalar().find('/') != std::string::npos;
    if (remote) {
      if (!in_3d())
        src.fail(to,
                 "a hook to another robot's task (ROBOT/TASK) rides the organism bus: only in a 3D world "
                 "(world: {kind: mujoco, bus: {...}})");
      if (!sc.organism.bus)
        src.fail(to,
                 "a hook to another robot's task (ROBOT/TASK) rides the organism bus, and this world has none: "
                 "add world.bus: {bandwidth: BITS_PER_SECOND, latency: DURATION}");
    } else {
      h.to = rd.task_name(to, "hook 'to'");
    }
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
    if (remote) {
      add_remote_hook(r, std::move(h), to);
      return;
    }
    add_hook(r, std::move(h), src.at(to));
  }

  // {from: TASK, to: ROBOT/TASK}: `from` is checked here, the other end once every robot is known.
  void add_remote_hook(RobotSpec& r, HookSpec h, const YAML::Node& to) {
    const std::string& text = to.Scalar();
    const std::size_t slash = text.find('/');
    const std::string robot = text.substr(0, slash), task = text.substr(slash + 1);
    if (!is_scenario_name(robot))
      src.fail(to, "'" + shown(robot) + "' in '" + shown(text) + "' is not a robot name; write ROBOT/TASK");
    if (!os::is_valid_name(task))
      src.fail(to, "'" + shown(task) + "' in '" + shown(text) + "' is not a task name; write ROBOT/TASK");
    if (!has_task(r, h.from)) no_task(r, h.from, h.where);
    for (const auto& o : r.remote_hooks)
      if (o.from == h.from && o.to_robot == robot && o.to == task && os::same_hook_key(o.options.port, h.options.port))
        src.fail(h.where, "hook " + h.from + " -> " + text + " is given twice (first at line " +
                              std::to_string(o.where.line) + ")");
    if (r.hooks.size() + r.remote_hooks.size() >= kMaxHooksPerRobot)
      src.fail(h.where, "more than " + std::to_string(kMaxHooksPerRobot) + " hooks for one robot");
    RemoteHookSpec rh;
    rh.from = h.from;
    rh.to_robot = robot;
    rh.to = task;
    rh.options = h.options;
    rh.where = h.where;
    rh.to_where = src.at(to);
    r.remote_hooks.push_back(std::move(rh));
  }

  std::optional<std::size_t> robot_index(std::string_view name) {
    if (robot_indices.size() != sc.robots.size())
      for (std::size_t i = robot_indices.size(); i < sc.robots.size(); ++i) robot_indices.emplace(sc.robots[i].name, i);
    if (auto it = robot_indices.find(name); it != robot_indices.end()) return it->second;
    return std::nullopt;
  }

  [[noreturn]] void no_robot(std::string_view name, const SourceLocation& where) const {
    std::vector<std::string_view> names;
    for (const auto& r : sc.robots) names.push_back(r.name);
    std::string msg = "there is no robot '" + shown(name) + "'";
    if (auto hint = os::closest_name(name, names); !hint.empty()) msg += " (did you mean '" + hint + "'?)";
    src.fail(where, msg);
  }

  void resolve_remote_hooks() {
    for (std::size_t i = 0; i < sc.robots.size(); ++i)
      for (RemoteHookSpec& h : sc.robots[i].remote_hooks) {
        const auto to = robot_index(h.to_robot);
        if (!to) no_robot(h.to_robot, h.to_where);
        if (*to == i)
          src.fail(h.to_where, "'" + h.to_robot + "' is this hook's own robot: hook its own task as 'from -> to'");
        if (!has_task(sc.robots[*to], h.to)) no_task(sc.robots[*to], h.to, h.to_where);
        h.to_index = *to;
      }
  }

  // A module kind file named by `module` (the node), read once however many robots name it.
  mujoco::ModuleKind module_kind(const YAML::Node& n, const std::string& name) {
    if (auto it = kinds.find(name); it != kinds.end()) return it->second;
    if (name.empty()) src.fail(n, "module names no file: module: modules/cube.yaml");
    auto text = read_kind(name);
    if (!text) src.fail(n, "cannot read module kind '" + shown(name) + "': " + text.error());
    namespace fs = std::filesystem;
    fs::path shown_path{name};
    if (shown_path.is_relative()) shown_path = fs::path(sc.base_dir) / shown_path;
    auto kind = mujoco::parse_module_kind(*text, shown_path.lexically_normal().string());
    if (!kind) throw Failure{kind.error() + " (the module kind named at " + src.at(n).str() + ")"};
    if (const std::string why = mujoco::check(*kind); !why.empty())
      src.fail(n, "module kind '" + shown(name) + "' cannot be built: " + why);
    kinds.emplace(name, *kind);
    return *kind;
  }

  // Where a module is on the floor: metres and radians, as the 3D world takes it.
  struct Placed {
    double x = 0, y = 0, yaw = 0;
  };

  static mujoco::Vec3 turned(double yaw, const mujoco::Vec3& v) {
    const double c = std::cos(yaw), s = std::sin(yaw);
    return {c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]};
  }
  static const mujoco::ConnectorSpec& connector(const RobotSpec& r, std::string_view name) {
    return *std::find_if(r.module_kind.connectors.begin(), r.module_kind.connectors.end(),
                         [&](const mujoco::ConnectorSpec& c) { return c.name == name; });
  }
  // The connector's centre in the world, the module at rest at `p` with its hinge straight.
  static mujoco::Vec3 connector_at(const RobotSpec& r, const Placed& p, const mujoco::ConnectorSpec& c) {
    const mujoco::Vec3 v = turned(p.yaw, c.position);
    return {p.x + v[0], p.y + v[1], mujoco::rest_height(r.module_kind) + v[2]};
  }

  // How far two modules' boxes (seen from above) reach into each other, m; <= 0 when apart. The
  // separating-axis test over the four edge directions of two rectangles.
  static double overlap(const RobotSpec& ra, const Placed& a, const RobotSpec& rb, const Placed& b) {
    const double d[2] = {b.x - a.x, b.y - a.y};
    double least = std::numeric_limits<double>::infinity();
    for (const double axis_yaw : {a.yaw, a.yaw + std::numbers::pi / 2, b.yaw, b.yaw + std::numbers::pi / 2}) {
      const double ax = std::cos(axis_yaw), ay = std::sin(axis_yaw);
      auto reach = [&](const RobotSpec& r, const Placed& p) {
        const auto& size = r.module_kind.body.size;
        return size[0] / 2 * std::abs(std::cos(p.yaw) * ax + std::sin(p.yaw) * ay) +
               size[1] / 2 * std::abs(-std::sin(p.yaw) * ax + std::cos(p.yaw) * ay);
      };
      least = std::min(least, reach(ra, a) + reach(rb, b) - std::abs(d[0] * ax + d[1] * ay));
    }
    return least;
  }

  static std::string mm(double metres) { return Reader::fmt(std::round(metres * 10000) / 10) + " mm"; }

  // Each organism (modules joined by world.docked) from the start of its first module in the
  // file, every other module where its dock puts it: turned so the two connectors face each other,
  // moved so they coincide. Then every pair is checked against the latch tolerances (a pair that
  // closes a ring, or joins kinds of different heights, may not meet) and no two bodies overlap.
  void place_modules() {
    const std::size_t n = sc.robots.size();
    const auto& docks = sc.organism.docked;
    std::vector<std::optional<Placed>> placed(n);
    std::vector<SourceLocation> placed_by(n);
    std::vector<std::size_t> placed_by_dock(n, mujoco::kNoIndex);
    std::vector<std::vector<std::size_t>> docks_of(n);
    for (std::size_t k = 0; k < docks.size(); ++k) {
      docks_of[docks[k].a].push_back(k);
      docks_of[docks[k].b].push_back(k);
    }
    for (std::size_t root = 0; root < n; ++root) {
      if (placed[root] || !given_start[root]) continue;
      const Pose& g = *given_start[root];
      placed[root] = Placed{g.x * kCm, g.y * kCm, g.theta};
      placed_by[root] = given_where[root];
      std::vector<std::size_t> queue{root};
      for (std::size_t qi = 0; qi < queue.size(); ++qi) {
        const std::size_t u = queue[qi];
        for (const std::size_t k : docks_of[u]) {
          const DockSpec& d = docks[k];
          const bool u_is_a = d.a == u;
          const std::size_t v = u_is_a ? d.b : d.a;
          if (placed[v]) continue;  // a ring: checked with every pair below
          if (given_start[v])
            src.fail(given_where[v], "robot '" + sc.robots[v].name + "' is placed by docking (world.docked, line " +
                                         std::to_string(d.where.line) + ") in the organism of '" +
                                         sc.robots[root].name +
                                         "', which has a start: an organism takes one "
                                         "start, its first module's; remove this one");
          const auto& cu = connector(sc.robots[u], u_is_a ? d.connector_a : d.connector_b);
          const auto& cv = connector(sc.robots[v], u_is_a ? d.connector_b : d.connector_a);
          const mujoco::Vec3 nu = turned(placed[u]->yaw, mujoco::face_normal(cu.face));
          const mujoco::Vec3 nv = mujoco::face_normal(cv.face);
          const double yaw = std::remainder(std::atan2(nu[1], nu[0]) + std::numbers::pi - std::atan2(nv[1], nv[0]),
                                            2 * std::numbers::pi);
          const mujoco::Vec3 at = connector_at(sc.robots[u], *placed[u], cu);
          const mujoco::Vec3 offset = turned(yaw, cv.position);
          placed[v] = Placed{at[0] - offset[0], at[1] - offset[1], yaw};
          placed_by[v] = d.where;
          placed_by_dock[v] = k;
          queue.push_back(v);
        }
      }
    }
    for (std::size_t i = 0; i < n; ++i)
      if (!placed[i]) {
        if (docks_of[i].empty())
          src.fail(sc.robots[i].where, "robot '" + sc.robots[i].name +
                                           "' has no start: give it start: {x: X, y: Y, heading: DEGREES}, or "
                                           "dock it (world.docked) to a module that has one");
        src.fail(docks[docks_of[i].front()].where,
                 "the organism of '" + sc.robots[i].name + "' has no start: give its first module a start");
      }
    for (std::size_t k = 0; k < docks.size(); ++k) {
      const DockSpec& d = docks[k];
      const RobotSpec &ra = sc.robots[d.a], &rb = sc.robots[d.b];
      const auto &ca = connector(ra, d.connector_a), &cb = connector(rb, d.connector_b);
      const mujoco::Vec3 pa = connector_at(ra, *placed[d.a], ca), pb = connector_at(rb, *placed[d.b], cb);
      const double distance = std::hypot(pa[0] - pb[0], pa[1] - pb[1], pa[2] - pb[2]);
      const mujoco::Vec3 na = turned(placed[d.a]->yaw, mujoco::face_normal(ca.face));
      const mujoco::Vec3 nb = turned(placed[d.b]->yaw, mujoco::face_normal(cb.face));
      const double angle = std::acos(std::clamp(-(na[0] * nb[0] + na[1] * nb[1] + na[2] * nb[2]), -1.0, 1.0));
      const std::string pair = ra.name + "." + d.connector_a + " and " + rb.name + "." + d.connector_b;
      if (distance > mujoco::kLatchPositionTolerance)
        src.fail(d.where,
                 pair + " cannot meet: placed " +
                     (placed_by_dock[d.a] == k || placed_by_dock[d.b] == k ? std::string("face to face")
                                                                           : std::string("by their other docks")) +
                     ", their centres are " + mm(distance) + " apart (" + mm(std::abs(pa[2] - pb[2])) +
                     " in height); latching needs at most " + mm(mujoco::kLatchPositionTolerance));
      if (angle > mujoco::kLatchAngleTolerance)
        src.fail(d.where, pair + " cannot meet: placed by their other docks, they face " +
                              Reader::fmt(std::round(angle * 1800 / std::numbers::pi) / 10) +
                              " degrees away from each other; latching needs at most 10");
    }
    for (std::size_t j = 0; j < n; ++j)
      for (std::size_t i = 0; i < j; ++i)
        if (const double o = overlap(sc.robots[i], *placed[i], sc.robots[j], *placed[j]); o > kModuleOverlapSlack)
          src.fail(placed_by[j], "robot '" + sc.robots[j].name + "' would start inside robot '" + sc.robots[i].name +
                                     "': their bodies overlap by " + mm(o));
    for (std::size_t i = 0; i < n; ++i) {
      RobotSpec& r = sc.robots[i];
      r.module_start = {placed[i]->x, placed[i]->y, placed[i]->yaw};
      r.start = Pose{placed[i]->x / kCm, placed[i]->y / kCm, placed[i]->yaw};
    }
  }

  // events: [{at: DURATION, robot: NAME, shell: LINE}, ...]
  void events(const YAML::Node& n) {
    for (const auto& item : rd.list(n, "events", kMaxEvents)) {
      Map m(src, item, "an event", {"at", "robot", "shell"});
      EventSpec e;
      e.where = src.at(item);
      e.at = rd.duration(m.require("at"), "event time 'at'", kernel::Duration{0}, sc.duration);
      const YAML::Node robot = m.require("robot");
      const std::string name = rd.text(robot, "event robot");
      const auto index = robot_index(name);
      if (!index) no_robot(name, src.at(robot));
      e.robot = *index;
      const YAML::Node line = m.require("shell");
      e.line = rd.text(line, "event shell line");
      auto tokens = shell::tokenize(e.line);
      if (!tokens) src.fail(line, "event shell line: " + tokens.error());
      if (tokens->empty()) src.fail(line, "event shell line has no command");
      const std::string& command = tokens->front().text;
      std::vector<std::string_view> commands;
      for (const auto& c : shell::Shell::commands()) commands.push_back(c.name);
      if (std::find(commands.begin(), commands.end(), command) == commands.end()) {
        std::string msg = "event shell line: unknown command '" + shown(command) + "'";
        if (auto hint = os::closest_name(command, commands); !hint.empty()) msg += " (did you mean '" + hint + "'?)";
        src.fail(line, msg);
      }
      sc.events.push_back(std::move(e));
    }
    std::stable_sort(sc.events.begin(), sc.events.end(),
                     [](const EventSpec& a, const EventSpec& b) { return a.at < b.at; });
  }

  // world.docked: [[a.back, b.front], ...]
  void docked() {
    std::map<std::pair<std::size_t, std::string>, SourceLocation> used;
    for (const auto& item : rd.list(docked_node, "docked", kMaxDocked)) {
      if (!item.IsSequence() || item.size() != 2)
        src.fail(item,
                 "a docked pair is [ROBOT.CONNECTOR, ROBOT.CONNECTOR], e.g. [m0.back, m1.front]" + Map::got(item));
      DockSpec d;
      d.where = src.at(item);
      std::size_t* robot[2] = {&d.a, &d.b};
      std::string* connector[2] = {&d.connector_a, &d.connector_b};
      for (int k = 0; k < 2; ++k) {
        const YAML::Node end = item[k];
        const std::string text = rd.text(end, "a docked connector");
        const std::size_t dot = text.find('.');
        if (dot == std::string::npos)
          src.fail(end, "'" + shown(text) + "' names no connector: write ROBOT.CONNECTOR, e.g. m0.back");
        const std::string rname = text.substr(0, dot), cname = text.substr(dot + 1);
        const auto index = robot_index(rname);
        if (!index) no_robot(rname, src.at(end));
        const mujoco::ModuleKind& kind = sc.robots[*index].module_kind;
        if (std::none_of(kind.connectors.begin(), kind.connectors.end(),
                         [&](const mujoco::ConnectorSpec& c) { return c.name == cname; })) {
          std::vector<std::string_view> names;
          for (const auto& c : kind.connectors) names.push_back(c.name);
          std::string msg =
              "robot '" + rname + "' (module kind '" + kind.name + "') has no connector '" + shown(cname) + "'";
          if (auto hint = os::closest_name(cname, names); !hint.empty()) msg += " (did you mean '" + hint + "'?)";
          src.fail(end, msg);
        }
        if (auto [it, fresh] = used.emplace(std::pair{*index, cname}, src.at(end)); !fresh)
          src.fail(end, "'" + text + "' is docked twice (first at line " + std::to_string(it->second.line) + ")");
        *robot[k] = *index;
        *connector[k] = cname;
      }
      if (d.a == d.b) src.fail(d.where, "robot '" + sc.robots[d.a].name + "' is docked to itself");
      sc.organism.docked.push_back(std::move(d));
    }
  }
};

}  // namespace

kernel::Result<Scenario> parse_scenario(std::string_view yaml_text, std::string_view file_name,
                                        const ScenarioParseOptions& options) {
  const std::string dir = std::filesystem::path(std::string(file_name)).parent_path().string();
  const std::string base_dir = dir.empty() ? "." : dir;
  ModuleKindReader reader = options.read_module_kind;
  if (!reader)
    reader = [base_dir](std::string_view name) -> kernel::Result<std::string> {
      std::filesystem::path p{std::string(name)};
      if (p.is_relative()) p = std::filesystem::path(base_dir) / p;
      return yaml::read_text_file(p.lexically_normal().string(), mujoco::kMaxModuleKindBytes, "module kind");
    };
  return yaml::parse_document<Scenario>(yaml_text, file_name, "a scenario", kMaxScenarioBytes, kMaxNesting,
                                        [&](const Source& src, const YAML::Node& root) {
                                          Parser p(src, reader);
                                          p.sc.file = std::string(file_name);
                                          p.sc.base_dir = base_dir;
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
