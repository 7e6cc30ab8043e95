// Fuzzes scenario files: bytes -> YAML -> Scenario, 2D and 3D. Any input must give a scenario or
// an error "fuzz.yaml:LINE:COLUMN: message" with LINE a line the input has, never a crash or a
// hang. Every accepted scenario must obey the rules the parser promises (robots inside the arena,
// clear of each other, unique names, hooks between existing tasks; in 3D, docks between two
// modules, finite starts, remote hooks and events that name robots that exist) and survive
// check_scenario. Module kind files are the shipped cube and long kinds, read once at the start
// and served from memory under the names modules/cube.yaml and modules/long.yaml: the fuzzed
// inputs never make the fuzzer read the disk.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <string_view>

#include "symb/sim/scenario.hpp"

using namespace symb;
using namespace symb::sim;

namespace {

long number_at(const std::string& e, std::size_t& i) {
  const std::size_t s = i;
  while (i < e.size() && i - s < 9 && std::isdigit(static_cast<unsigned char>(e[i]))) ++i;
  return i == s ? -1 : std::stol(e.substr(s, i - s));
}

bool located(const std::string& e, std::string_view text) {
  const std::string prefix = "fuzz.yaml:";
  if (e.rfind(prefix, 0) != 0) return false;
  std::size_t i = prefix.size();
  const long line = number_at(e, i);
  if (i >= e.size() || e[i++] != ':') return false;
  const long column = number_at(e, i);
  if (e.compare(i, 2, ": ") != 0 || e.size() <= i + 2) return false;
  long lines = static_cast<long>(std::count(text.begin(), text.end(), '\n'));
  if (!text.empty() && text.back() != '\n') ++lines;
  return line >= 1 && line <= std::max(lines, 1L) && column >= 1;
}

// scenarios/modules/cube.yaml and long.yaml without their comments.
// The shipped kind files, read once: the fuzzer serves exactly what scenarios name, and a kind
// file that changes cannot leave a stale copy here.
std::string shipped_kind(const char* file) {
  std::ifstream in(std::string(SYMB_SCENARIO_DIR) + "/modules/" + file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in || text.str().empty()) std::abort();
  return text.str();
}

const ScenarioParseOptions& from_memory() {
  static const ScenarioParseOptions options = [] {
    ScenarioParseOptions o;
    o.read_module_kind = [cube = shipped_kind("cube.yaml"),
                          long_kind = shipped_kind("long.yaml")](std::string_view name) -> kernel::Result<std::string> {
      if (name == "modules/cube.yaml") return cube;
      if (name == "modules/long.yaml") return long_kind;
      return kernel::Error{"no such kind file (the fuzzer serves modules/cube.yaml and modules/long.yaml)"};
    };
    return o;
  }();
  return options;
}

const os::TaskTypeRegistry& registry() {
  static const os::TaskTypeRegistry reg = [] {
    os::TaskTypeRegistry r;
    os::TaskType t;
    t.name = "mdl2e";
    t.params = {{"program", os::ParamType::kString, std::string(), {}, {}, ""},
                {"speed_limit", os::ParamType::kReal, 500.0, 0.0, 500.0, ""}};
    t.make = [](const os::ParamSet&) { return std::unique_ptr<os::Task>(); };
    if (!r.add(t)) std::abort();
    return r;
  }();
  return reg;
}

void check_sound_3d(const Scenario& sc) {
  if (sc.robots.empty() || sc.robots.size() > kMaxRobots) std::abort();
  const std::size_t n = sc.robots.size();
  for (std::size_t i = 0; i < n; ++i) {
    const RobotSpec& r = sc.robots[i];
    for (std::size_t j = 0; j < i; ++j)
      if (r.name == sc.robots[j].name) std::abort();
    if (!std::isfinite(r.module_start.x) || !std::isfinite(r.module_start.y) || !std::isfinite(r.module_start.yaw))
      std::abort();
    if (r.module_kind.connectors.empty() || r.module.empty()) std::abort();
    for (const auto& h : r.remote_hooks)
      if (h.to_index >= n || h.to_index == i || sc.robots[h.to_index].name != h.to_robot || !sc.organism.bus)
        std::abort();
  }
  for (const auto& d : sc.organism.docked)
    if (d.a >= n || d.b >= n || d.a == d.b) std::abort();
  for (const auto& e : sc.events)
    if (e.robot >= n || e.at > sc.duration || e.at.count() < 0) std::abort();
}

void check_sound(const Scenario& sc) {
  if (sc.world_kind == WorldKind::kMujoco) return check_sound_3d(sc);
  const WorldSpec& w = sc.world;
  if (!(w.width > 0 && w.height > 0) || sc.robots.empty() || sc.robots.size() > kMaxRobots) std::abort();
  for (std::size_t i = 0; i < sc.robots.size(); ++i) {
    const RobotSpec& r = sc.robots[i];
    if (std::min({r.start.x, r.start.y, w.width - r.start.x, w.height - r.start.y}) < kStartClearance) std::abort();
    if (!std::isfinite(r.start.theta)) std::abort();
    for (std::size_t j = 0; j < i; ++j)
      if (r.name == sc.robots[j].name) std::abort();
    for (const auto& h : r.hooks) {
      if (h.from == h.to) std::abort();
      for (const std::string* end : {&h.from, &h.to}) {
        const bool known = is_device_task_name(*end) || std::any_of(r.tasks.begin(), r.tasks.end(),
                                                                    [&](const TaskSpec& t) { return t.name == *end; });
        if (!known) std::abort();
      }
    }
    for (const auto& t : r.tasks)
      if (t.params.size() != t.param_where.size()) std::abort();
  }
  for (const auto& e : sc.events)
    if (e.robot >= sc.robots.size() || e.at > sc.duration || e.at.count() < 0) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto sc = parse_scenario(text, "fuzz.yaml", from_memory());
  if (!sc) {
    if (!located(sc.error(), text)) std::abort();
    return 0;
  }
  check_sound(*sc);
  auto st = check_scenario(*sc, registry());
  if (!st && !located(st.error(), text)) std::abort();
  return 0;
}
