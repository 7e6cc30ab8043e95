// Scenario files -> Scenario. yaml-cpp does the YAML; everything after that is a walk over the
// tree that knows the schema, so each value is read exactly once and an error can name the line
// and column of the value that caused it. Internally a failure is thrown as `Failure` (the walk
// is deep and every step can fail); parse_scenario catches it and everything yaml-cpp throws,
// so no exception leaves this file.
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

struct Failure {
  std::string message;
};

// The text of a value for an error message: short and printable.
std::string shown(std::string_view s) {
  std::string out;
  for (char ch : s.substr(0, 40)) {
    const auto c = static_cast<unsigned char>(ch);
    out += (c >= 0x20 && c < 0x7f) ? ch : '?';
  }
  if (s.size() > 40) out += "...";
  return out;
}

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

// Locations and failures for one file.
class Source {
 public:
  Source(std::string_view file, std::string_view text) : file_(file) {
    // Marks past the end (yaml-cpp reports "end of stream" after the last newline) are pulled
    // back onto the last line, so every error names a line the file has.
    lines_ = 1;
    std::size_t last_start = 0;
    for (std::size_t i = 0; i < text.size(); ++i)
      if (text[i] == '\n' && i + 1 < text.size()) {
        ++lines_;
        last_start = i + 1;
      }
    std::size_t end = text.size();
    while (end > last_start && (text[end - 1] == '\n' || text[end - 1] == '\r')) --end;
    last_line_length_ = static_cast<int>(end - last_start);
  }

  const std::string& file() const { return file_; }

  SourceLocation at(const YAML::Mark& m, int column_offset = 0) const {
    SourceLocation loc{file_, 1, 1};
    if (m.is_null() || m.line < 0) return loc;
    if (m.line + 1 > lines_) {
      loc.line = lines_;
      loc.column = last_line_length_ + 1;
      return loc;
    }
    loc.line = m.line + 1;
    loc.column = std::max(0, m.column) + 1 + column_offset;
    return loc;
  }
  SourceLocation at(const YAML::Node& n) const { return at(n.Mark()); }

  [[noreturn]] void fail(const SourceLocation& where, const std::string& what) const {
    throw Failure{where.str() + ": " + what};
  }
  [[noreturn]] void fail(const YAML::Node& n, const std::string& what) const { fail(at(n), what); }

 private:
  std::string file_;
  int lines_ = 1;
  int last_line_length_ = 0;
};

// Zeroth pass, over the bytes: flow collections ('[' and '{') nested deeper than kMaxNesting.
// yaml-cpp's scanner reads a flow collection ahead before it hands over its first event (any '['
// may start a simple key), about 2.5 us a byte: a MiB of '[' cost 2.5 s before the event pass
// could stop it; this finds the first bracket past the bound in a millisecond. It counts only the
// brackets that open a collection (any in flow context; in block context one that starts a value
// or a line), skips quoted scalars, comments and block scalars ('|', '>'), and stops counting at
// anything it cannot place (an unterminated quote), so it never rejects a file that nests less;
// the event pass below stays the authority. Returns the 1-based line and column of the bracket.
std::optional<std::pair<int, int>> flow_too_deep(std::string_view t) {
  int depth = 0, line = 1;
  std::size_t line_start = 0;
  char prev = '\n';              // the last character that is not a blank on this line; '\n' at its start
  bool blank_before = true;      // a blank (or the line start) comes right before i
  int block_scalar_indent = -1;  // >= 0: inside a block scalar's lines, indented more than this
  for (std::size_t i = 0; i < t.size(); ++i) {
    const char c = t[i];
    if (c == '\n') {
      ++line;
      line_start = i + 1;
      prev = '\n';
      blank_before = true;
      if (block_scalar_indent >= 0) {  // skip the scalar's lines: blank ones or indented deeper
        std::size_t k = i + 1;
        for (;;) {
          std::size_t e = k;
          while (e < t.size() && t[e] == ' ') ++e;
          if (e < t.size() && t[e] != '\n' && t[e] != '\r' && static_cast<int>(e - k) <= block_scalar_indent) break;
          const std::size_t nl = t.find('\n', e);
          if (nl == std::string_view::npos) return std::nullopt;
          ++line;
          k = nl + 1;
        }
        line_start = k;
        i = k - 1;
        block_scalar_indent = -1;
      }
      continue;
    }
    if (c == ' ' || c == '\t' || c == '\r') {
      blank_before = true;
      continue;
    }
    const bool token_start = blank_before || prev == '[' || prev == '{' || prev == ',';
    if (c == '#' && blank_before) {
      const std::size_t nl = t.find('\n', i);
      if (nl == std::string_view::npos) return std::nullopt;
      i = nl - 1;
      continue;
    }
    if ((c == '\'' || c == '"') && token_start) {
      std::size_t k = i + 1;
      for (;; ++k) {
        if (k >= t.size()) return std::nullopt;
        if (t[k] == '\n') {
          ++line;
          line_start = k + 1;
        } else if (c == '"' && t[k] == '\\') {
          ++k;
        } else if (t[k] == c) {
          if (c == '\'' && k + 1 < t.size() && t[k + 1] == '\'') {
            ++k;
            continue;
          }
          break;
        }
      }
      i = k;
      prev = c;
      blank_before = false;
      continue;
    }
    if ((c == '|' || c == '>') && depth == 0 && blank_before && prev == ':') {
      std::size_t indent = 0;
      while (line_start + indent < t.size() && t[line_start + indent] == ' ') ++indent;
      block_scalar_indent = static_cast<int>(indent);
    } else if ((c == '[' || c == '{') &&
               (depth > 0 || (blank_before && (prev == '\n' || prev == ':' || prev == '-' || prev == '?')))) {
      if (++depth > kMaxNesting) return std::pair{line, static_cast<int>(i - line_start) + 1};
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
    prev = c;
    blank_before = false;
  }
  return std::nullopt;
}

// First pass over the events: nesting depth and document count, before any tree is built.
// yaml-cpp recurses once per level (it stops itself at 2000); this stops at kMaxNesting.
class ShapeCheck : public YAML::EventHandler {
 public:
  explicit ShapeCheck(const Source& src) : src_(src) {}
  void OnDocumentStart(const YAML::Mark& m) override {
    if (++documents_ > 1) src_.fail(src_.at(m), "a scenario file holds one YAML document; this is a second one");
  }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t, const std::string&) override {}
  void OnSequenceStart(const YAML::Mark& m, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    enter(m);
  }
  void OnSequenceEnd() override { --depth_; }
  void OnMapStart(const YAML::Mark& m, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    enter(m);
  }
  void OnMapEnd() override { --depth_; }

 private:
  void enter(const YAML::Mark& m) {
    if (++depth_ > kMaxNesting)
      src_.fail(src_.at(m), "nested more than " + std::to_string(kMaxNesting) + " levels deep");
  }
  const Source& src_;
  int documents_ = 0;
  int depth_ = 0;
};

// A mapping whose keys are checked against a schema: known, plain, each once.
class Map {
 public:
  Map(const Source& src, const YAML::Node& node, std::string_view what, std::initializer_list<std::string_view> keys)
      : src_(src), node_(node), what_(what) {
    if (!node.IsMap()) src.fail(node, std::string(what) + " must be a mapping (key: value, ...)" + got(node));
    const std::vector<std::string_view> known(keys);
    for (const auto& kv : node) {
      const YAML::Node& k = kv.first;
      if (!k.IsScalar()) src.fail(k, "a key in " + std::string(what) + " must be a plain name");
      const std::string& name = k.Scalar();
      if (std::find(known.begin(), known.end(), name) == known.end()) {
        std::string msg = "unknown key '" + shown(name) + "' in " + std::string(what);
        if (auto hint = os::closest_name(name, known); !hint.empty()) {
          msg += " (did you mean '" + hint + "'?)";
        } else {
          msg += " (known keys:";
          for (auto kn : known) msg += " " + std::string(kn);
          msg += ")";
        }
        src.fail(k, msg);
      }
      for (const auto& e : entries_)
        if (e.name == name)
          src.fail(k, "key '" + name + "' given twice in " + std::string(what) + " (first at line " +
                          std::to_string(src.at(e.key).line) + ")");
      entries_.push_back({name, k, kv.second});
    }
  }

  // The value of `key`; an undefined node when absent.
  YAML::Node get(std::string_view key) const {
    for (const auto& e : entries_)
      if (e.name == key) return e.value;
    return YAML::Node(YAML::NodeType::Undefined);
  }
  bool has(std::string_view key) const { return get(key).IsDefined(); }
  YAML::Node require(std::string_view key) const {
    YAML::Node v = get(key);
    if (!v.IsDefined()) src_.fail(node_, std::string(what_) + " needs '" + std::string(key) + "'");
    return v;
  }
  const YAML::Node& node() const { return node_; }

  static std::string got(const YAML::Node& n) {
    switch (n.Type()) {
      case YAML::NodeType::Null: return ", got nothing";
      case YAML::NodeType::Scalar: return ", got '" + shown(n.Scalar()) + "'";
      case YAML::NodeType::Sequence: return ", got a sequence";
      case YAML::NodeType::Map: return ", got a mapping";
      default: return "";
    }
  }

 private:
  struct Entry {
    std::string name;
    YAML::Node key;
    YAML::Node value;
  };
  const Source& src_;
  YAML::Node node_;
  std::string what_;
  std::vector<Entry> entries_;
};

class Reader {
 public:
  explicit Reader(const Source& src) : src_(src) {}

  std::string text(const YAML::Node& n, std::string_view what) const {
    if (!n.IsScalar()) src_.fail(n, std::string(what) + " must be a single value" + Map::got(n));
    return n.Scalar();
  }

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

  double number(const YAML::Node& n, std::string_view what, double lo, double hi) const {
    const std::string s = text(n, what);
    std::string_view v = s;
    if (!v.empty() && v.front() == '+') v.remove_prefix(1);
    double d = 0;
    auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), d);
    if (v.empty() || ec != std::errc() || end != v.data() + v.size() || !std::isfinite(d))
      src_.fail(n, std::string(what) + " must be a finite number, got '" + shown(s) + "'");
    if (d < lo || d > hi)
      src_.fail(n, std::string(what) + " must be in " + fmt(lo) + ".." + fmt(hi) + ", got " + shown(s));
    return d;
  }

  std::int64_t integer(const YAML::Node& n, std::string_view what, std::int64_t lo, std::int64_t hi) const {
    const std::string s = text(n, what);
    std::string_view v = s;
    if (!v.empty() && v.front() == '+') v.remove_prefix(1);
    std::int64_t i = 0;
    auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), i);
    if (v.empty() || ec != std::errc() || end != v.data() + v.size() || i < lo || i > hi)
      src_.fail(n, std::string(what) + " must be an integer in " + std::to_string(lo) + ".." + std::to_string(hi) +
                       ", got '" + shown(s) + "'");
    return i;
  }

  std::uint64_t unsigned_integer(const YAML::Node& n, std::string_view what) const {
    const std::string s = text(n, what);
    std::uint64_t u = 0;
    auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), u);
    if (s.empty() || ec != std::errc() || end != s.data() + s.size())
      src_.fail(n, std::string(what) + " must be an unsigned integer (0.." +
                       std::to_string(std::numeric_limits<std::uint64_t>::max()) + "), got '" + shown(s) + "'");
    return u;
  }

  bool boolean(const YAML::Node& n, std::string_view what) const {
    const std::string s = text(n, what);
    if (s == "true" || s == "True" || s == "TRUE") return true;
    if (s == "false" || s == "False" || s == "FALSE") return false;
    src_.fail(n, std::string(what) + " must be true or false, got '" + shown(s) + "'");
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

  // A list that may also be written as nothing at all (`tasks:` with no entries).
  std::vector<YAML::Node> list(const YAML::Node& n, std::string_view what, std::size_t max) const {
    std::vector<YAML::Node> out;
    if (!n.IsDefined() || n.IsNull()) return out;
    if (!n.IsSequence()) src_.fail(n, std::string(what) + " must be a list (- item, or [a, b])" + Map::got(n));
    if (n.size() > max)
      src_.fail(n, std::string(what) + " has " + std::to_string(n.size()) + " entries; at most " + std::to_string(max) +
                       " are allowed");
    for (const auto& item : n) out.push_back(item);
    return out;
  }

  std::pair<double, double> point(const YAML::Node& n, std::string_view what, const WorldSpec& w) const {
    auto xy = list(n, what, 2);
    if (!n.IsSequence() || xy.size() != 2) src_.fail(n, std::string(what) + " must be a point [x, y]" + Map::got(n));
    return {number(xy[0], "x", 0, w.width), number(xy[1], "y", 0, w.height)};
  }

  static std::string fmt(double v) {
    std::ostringstream o;
    o << v;
    return o.str();
  }
  static std::string fmt_duration(kernel::Duration d) { return os::format_param_value(os::ParamValue{d}); }

 private:
  const Source& src_;
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
  const Source src(file_name, yaml_text);
  const SourceLocation start{src.file(), 1, 1};
  try {
    if (yaml_text.size() > kMaxScenarioBytes)
      return Error{start.str() + ": the file has " + std::to_string(yaml_text.size()) +
                   " bytes; a scenario may have at most 1 MiB"};
    if (const auto deep = flow_too_deep(yaml_text))
      return Error{SourceLocation{src.file(), deep->first, deep->second}.str() + ": nested more than " +
                   std::to_string(kMaxNesting) + " levels deep"};
    const std::string text(yaml_text);
    {
      std::istringstream in(text);
      YAML::Parser events(in);
      ShapeCheck shape(src);
      while (events.HandleNextDocument(shape)) {
      }
    }
    Parser p(src);
    p.sc.file = std::string(file_name);
    const std::string dir = std::filesystem::path(p.sc.file).parent_path().string();
    p.sc.base_dir = dir.empty() ? "." : dir;
    p.top(YAML::Load(text));
    return std::move(p.sc);
  } catch (const Failure& f) {
    return Error{f.message};
  } catch (const YAML::Exception& e) {
    return Error{src.at(e.mark).str() + ": invalid YAML: " + e.msg};
  } catch (const std::exception& e) {
    return Error{start.str() + ": cannot read the scenario: " + e.what()};
  } catch (...) {
    return Error{start.str() + ": cannot read the scenario"};
  }
}

kernel::Result<Scenario> load_scenario(const std::string& path) {
  const std::string where = SourceLocation{path}.str();
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status))
    return Error{where + ": cannot open the scenario file" + (ec ? " (" + ec.message() + ")" : std::string())};
  if (!std::filesystem::is_regular_file(status)) return Error{where + ": not a regular file"};
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{where + ": cannot open the scenario file"};
  std::string text(kMaxScenarioBytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  if (in.bad()) return Error{where + ": cannot read the scenario file"};
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > kMaxScenarioBytes) return Error{where + ":1:1: the file is larger than 1 MiB"};
  auto sc = parse_scenario(text, path);
  if (!sc) return sc;
  Scenario out = std::move(sc).value();
  const std::string dir = std::filesystem::path(path).parent_path().string();
  out.base_dir = dir.empty() ? "." : dir;
  return out;
}

}  // namespace symb::sim
