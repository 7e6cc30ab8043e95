#include "symb/evo/embryogenesis/task_graph_genome.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <set>
#include <utility>

#include "symb/evo/genome/real_genome.hpp"
#include "symb/kernel/source_text.hpp"

namespace symb::evo {

namespace {

using kernel::Error;

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r'; }

std::string shorten(std::string_view s) {
  std::string out(s.substr(0, 40));
  for (char& c : out)
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = '?';
  return s.size() > 40 ? out + "..." : out;
}

// A cursor over one line that reports 1-based columns.
struct LineCursor {
  std::string_view line;
  std::size_t number = 0;
  std::size_t i = 0;

  void skip_spaces() {
    while (i < line.size() && is_space(line[i])) ++i;
  }
  bool at_end() {
    skip_spaces();
    return i >= line.size();
  }
  std::size_t column() const { return i + 1; }
  // A word: up to the next space (or `stop`, when given).
  std::string_view word(std::string_view stop = {}) {
    skip_spaces();
    const std::size_t start = i;
    while (i < line.size() && !is_space(line[i]) && (stop.empty() || line.substr(i).substr(0, stop.size()) != stop))
      ++i;
    if (!stop.empty() && i == start) return {};
    return line.substr(start, i - start);
  }
  std::string error(std::size_t col, const std::string& msg) const {
    return kernel::location_prefix(number, col) + msg;
  }
};

kernel::Result<std::string> name_at(LineCursor& c, const char* what) {
  const std::size_t col = (c.skip_spaces(), c.column());
  const std::string_view w = c.word("->");
  if (w.empty()) return Error{c.error(col, std::string("expected ") + what)};
  if (!os::is_valid_name(w))
    return Error{c.error(col, "'" + shorten(w) + "' is not a valid " + what +
                                  " (1 to 63 of A-Z a-z 0-9 _ . -, starting with a letter or _)")};
  return std::string(w);
}

kernel::Result<std::int64_t> integer_at(LineCursor& c, const char* what, std::int64_t lo, std::int64_t hi) {
  const std::size_t col = (c.skip_spaces(), c.column());
  const std::string_view w = c.word();
  std::int64_t v = 0;
  const auto [end, ec] = std::from_chars(w.data(), w.data() + w.size(), v);
  if (w.empty() || ec != std::errc{} || end != w.data() + w.size())
    return Error{c.error(col, std::string("expected ") + what + " (a whole number), got '" + shorten(w) + "'")};
  if (v < lo || v > hi)
    return Error{c.error(col, std::string(what) + " " + std::to_string(v) + " is outside " + std::to_string(lo) + ".." +
                                  std::to_string(hi))};
  return v;
}

kernel::Status parse_task(LineCursor& c, TaskGraphGenome& g) {
  if (g.tasks.size() >= kMaxGraphTasks)
    return Error{c.error(1, "more than " + std::to_string(kMaxGraphTasks) + " tasks")};
  TaskGene t;
  t.line = c.number;
  auto name = name_at(c, "task name");
  if (!name) return Error{name.error()};
  t.name = *name;
  auto type = name_at(c, "task type");
  if (!type) return Error{type.error()};
  t.type = *type;
  c.skip_spaces();
  const std::size_t offset = c.i;
  auto params = os::parse_param_assignments(c.line.substr(offset));
  if (!params) {
    // "column N: ..." is relative to the parameter list: make it the line's.
    std::string e = params.error();
    std::size_t col = 0;
    if (e.rfind("column ", 0) == 0) {
      std::size_t k = 7;
      while (k < e.size() && e[k] >= '0' && e[k] <= '9') col = col * 10 + static_cast<std::size_t>(e[k++] - '0');
      if (k < e.size() && e[k] == ':') {
        std::size_t rest = k + 1;
        while (rest < e.size() && e[rest] == ' ') ++rest;
        return Error{c.error(col + offset, e.substr(rest))};
      }
    }
    return Error{c.error(offset + 1, e)};
  }
  std::vector<os::ParamAssignment> list = std::move(params).value();
  std::set<std::string, std::less<>> seen;
  for (os::ParamAssignment& a : list) {
    a.column += offset;
    if (!seen.insert(a.name).second) return Error{c.error(a.column, "parameter '" + a.name + "' given twice")};
  }
  t.params = std::move(list);
  g.tasks.push_back(std::move(t));
  return {};
}

kernel::Status parse_hook(LineCursor& c, TaskGraphGenome& g) {
  if (g.hooks.size() >= kMaxGraphHooks)
    return Error{c.error(1, "more than " + std::to_string(kMaxGraphHooks) + " hooks")};
  HookGene h;
  h.line = c.number;
  auto from = name_at(c, "sender task name");
  if (!from) return Error{from.error()};
  h.from = *from;
  c.skip_spaces();
  if (c.line.substr(c.i).substr(0, 2) != "->")
    return Error{c.error(c.column(), "expected '->' after the sender (hook FROM -> TO [port N] [priority P])")};
  c.i += 2;
  auto to = name_at(c, "receiver task name");
  if (!to) return Error{to.error()};
  h.to = *to;
  bool have_priority = false;
  while (!c.at_end()) {
    const std::size_t col = c.column();
    const std::string_view key = c.word();
    if (key == "port" && !h.port) {
      auto p = integer_at(c, "port", 0, 65535);
      if (!p) return Error{p.error()};
      h.port = static_cast<std::int32_t>(*p);
    } else if (key == "priority" && !have_priority) {
      auto p = integer_at(c, "priority", -1000, 1000);
      if (!p) return Error{p.error()};
      h.priority = static_cast<int>(*p);
      have_priority = true;
    } else if (key == "port" || key == "priority") {
      return Error{c.error(col, "'" + std::string(key) + "' given twice")};
    } else {
      return Error{c.error(col, "unknown hook option '" + shorten(key) + "' (port N, priority P)")};
    }
  }
  g.hooks.push_back(std::move(h));
  return {};
}

bool needs_quotes(std::string_view v) {
  if (v.empty()) return true;
  return std::any_of(v.begin(), v.end(), [](char ch) { return is_space(ch) || ch == '"' || ch == '\\' || ch == '\n'; });
}

std::string quoted(std::string_view v) {
  if (!needs_quotes(v)) return std::string(v);
  std::string out = "\"";
  for (char ch : v) {
    if (ch == '"' || ch == '\\') out += '\\';
    out += ch;
  }
  return out + "\"";
}

template <typename T>
const T& pick(const std::vector<T>& v, kernel::RandomStream& random) {
  return v[static_cast<std::size_t>(random.below(v.size()))];
}

// A new value of `spec` near `current` (or its default), within its range; nullopt for a type
// the operator does not change (strings: their meaning is the type's own business).
std::optional<os::ParamValue> new_value(const os::ParamSpec& spec, const os::ParamValue& current,
                                        kernel::RandomStream& random, double share) {
  const double lo = spec.min.value_or(-1e6), hi = spec.max.value_or(1e6);
  switch (spec.type) {
    case os::ParamType::kBool: return os::ParamValue(!std::get<bool>(current));
    case os::ParamType::kInt: {
      double step = std::round(random.normal() * share * (hi - lo));
      if (step == 0) step = random.below(2) ? 1.0 : -1.0;  // an integer always moves
      const double x = reflect(static_cast<double>(std::get<std::int64_t>(current)) + step, lo, hi);
      return os::ParamValue(static_cast<std::int64_t>(std::clamp(std::round(x), std::ceil(lo), std::floor(hi))));
    }
    case os::ParamType::kReal:
      return os::ParamValue(reflect(std::get<double>(current) + random.normal() * share * (hi - lo), lo, hi));
    case os::ParamType::kDuration: {
      const double s = std::chrono::duration<double>(std::get<kernel::Duration>(current)).count();
      const double x = reflect(s + random.normal() * share * (hi - lo), lo, hi);
      // Whole microseconds, inside the range after the rounding.
      auto d =
          std::chrono::duration_cast<kernel::Duration>(std::chrono::microseconds(static_cast<std::int64_t>(x * 1e6)));
      if (!os::check_param_value(spec, d)) d = std::get<kernel::Duration>(spec.default_value);
      return os::ParamValue(d);
    }
    case os::ParamType::kString: return std::nullopt;
  }
  return std::nullopt;
}

bool mutable_param(const os::ParamSpec& s) { return s.type != os::ParamType::kString; }

std::vector<std::string> hookable_names(const TaskGraphGenome& g, const GraphMutationOptions& options) {
  std::vector<std::string> names;
  for (const TaskGene& t : g.tasks) names.push_back(t.name);
  for (const std::string& e : options.external_tasks)
    if (!g.find_task(e)) names.push_back(e);
  return names;
}

}  // namespace

bool TaskGene::operator==(const TaskGene& o) const {
  if (name != o.name || type != o.type || params.size() != o.params.size()) return false;
  for (std::size_t i = 0; i < params.size(); ++i)
    if (params[i].name != o.params[i].name || params[i].value != o.params[i].value) return false;
  return true;
}

const TaskGene* TaskGraphGenome::find_task(std::string_view name) const {
  for (const TaskGene& t : tasks)
    if (t.name == name) return &t;
  return nullptr;
}

kernel::Result<TaskGraphGenome> parse_task_graph(std::string_view text) {
  if (text.size() > kMaxGraphText)
    return Error{"1:1: the text has " + std::to_string(text.size()) + " bytes, more than " +
                 std::to_string(kMaxGraphText)};
  TaskGraphGenome g;
  std::size_t number = 0;
  while (!text.empty() || number == 0) {
    const std::size_t nl = text.find('\n');
    LineCursor c{text.substr(0, nl), ++number, 0};
    text = nl == std::string_view::npos ? std::string_view{} : text.substr(nl + 1);
    if (c.at_end() || c.line[c.i] == '#') {
      if (text.empty()) break;
      continue;
    }
    const std::size_t col = c.column();
    const std::string_view keyword = c.word();
    kernel::Status st;
    if (keyword == "task")
      st = parse_task(c, g);
    else if (keyword == "hook")
      st = parse_hook(c, g);
    else if (keyword == "ports")
      st = Error{c.error(col,
                         "a genome declares no ports: each task's port layouts come from its task type "
                         "(and a device task's from the node), and every hook is checked against them")};
    else
      st = Error{c.error(col, "unknown statement '" + shorten(keyword) + "' (task, hook)")};
    if (!st) return Error{st.error()};
    if (text.empty()) break;
  }
  return g;
}

std::string to_text(const TaskGraphGenome& genome) {
  std::string out;
  for (const TaskGene& t : genome.tasks) {
    out += "task " + t.name + " " + t.type;
    for (const os::ParamAssignment& a : t.params) out += " " + a.name + "=" + quoted(a.value);
    out += '\n';
  }
  for (const HookGene& h : genome.hooks) {
    out += "hook " + h.from + " -> " + h.to;
    if (h.port) out += " port " + std::to_string(*h.port);
    if (h.priority != 0) out += " priority " + std::to_string(h.priority);
    out += '\n';
  }
  return out;
}

const char* to_string(GraphMutation m) {
  switch (m) {
    case GraphMutation::kParameter: return "parameter";
    case GraphMutation::kAddTask: return "add_task";
    case GraphMutation::kRemoveTask: return "remove_task";
    case GraphMutation::kAddHook: return "add_hook";
    case GraphMutation::kRemoveHook: return "remove_hook";
  }
  return "?";
}

bool mutate_parameter(TaskGraphGenome& g, const os::TaskTypeRegistry& registry, kernel::RandomStream& random,
                      const GraphMutationOptions& options) {
  std::vector<std::size_t> candidates;
  for (std::size_t i = 0; i < g.tasks.size(); ++i)
    if (const os::TaskType* type = registry.find(g.tasks[i].type))
      if (std::any_of(type->params.begin(), type->params.end(), mutable_param)) candidates.push_back(i);
  if (candidates.empty()) return false;
  TaskGene& task = g.tasks[pick(candidates, random)];
  const os::TaskType& type = *registry.find(task.type);
  std::vector<const os::ParamSpec*> specs;
  for (const os::ParamSpec& s : type.params)
    if (mutable_param(s)) specs.push_back(&s);
  const os::ParamSpec& spec = *pick(specs, random);
  auto it = std::find_if(task.params.begin(), task.params.end(),
                         [&](const os::ParamAssignment& a) { return a.name == spec.name; });
  os::ParamValue current = spec.default_value;
  if (it != task.params.end())
    if (auto v = os::parse_param_value(spec, it->value)) current = *v;
  auto next = new_value(spec, current, random, options.step_share);
  if (!next) return false;
  const std::string text = os::format_param_value(*next);
  if (it != task.params.end())
    it->value = text;
  else
    task.params.push_back({spec.name, text, 0});
  return true;
}

bool add_task(TaskGraphGenome& g, const os::TaskTypeRegistry& registry, kernel::RandomStream& random,
              const GraphMutationOptions& options) {
  if (g.tasks.size() >= kMaxGraphTasks) return false;
  std::vector<std::string> types;
  for (const std::string& t : options.addable_types)
    if (registry.find(t)) types.push_back(t);
  if (options.addable_types.empty())
    for (const os::TaskType* t : registry.list()) types.push_back(t->name);
  if (types.empty()) return false;
  TaskGene t;
  t.type = pick(types, random);
  for (std::size_t k = g.tasks.size();; ++k) {
    t.name = "g" + std::to_string(k);
    if (!g.find_task(t.name) &&
        std::find(options.external_tasks.begin(), options.external_tasks.end(), t.name) == options.external_tasks.end())
      break;
  }
  g.tasks.push_back(std::move(t));
  return true;
}

bool remove_task(TaskGraphGenome& g, kernel::RandomStream& random) {
  if (g.tasks.empty()) return false;
  const auto i = static_cast<std::ptrdiff_t>(random.below(g.tasks.size()));
  const std::string name = g.tasks[static_cast<std::size_t>(i)].name;
  g.tasks.erase(g.tasks.begin() + i);
  std::erase_if(g.hooks, [&](const HookGene& h) { return h.from == name || h.to == name; });
  return true;
}

bool add_hook(TaskGraphGenome& g, kernel::RandomStream& random, const GraphMutationOptions& options) {
  if (g.hooks.size() >= kMaxGraphHooks) return false;
  const std::vector<std::string> names = hookable_names(g, options);
  std::vector<std::pair<std::size_t, std::size_t>> free;
  for (std::size_t a = 0; a < names.size(); ++a)
    for (std::size_t b = 0; b < names.size(); ++b) {
      if (a == b) continue;
      const bool taken = std::any_of(g.hooks.begin(), g.hooks.end(), [&](const HookGene& h) {
        return h.from == names[a] && h.to == names[b] && !h.port;
      });
      if (!taken) free.emplace_back(a, b);
    }
  if (free.empty()) return false;
  const auto& chosen = pick(free, random);
  HookGene h;
  h.from = names[chosen.first];
  h.to = names[chosen.second];
  g.hooks.push_back(std::move(h));
  return true;
}

bool remove_hook(TaskGraphGenome& g, kernel::RandomStream& random) {
  if (g.hooks.empty()) return false;
  g.hooks.erase(g.hooks.begin() + static_cast<std::ptrdiff_t>(random.below(g.hooks.size())));
  return true;
}

std::optional<GraphMutation> mutate(TaskGraphGenome& g, const os::TaskTypeRegistry& registry,
                                    kernel::RandomStream& random, const GraphMutationOptions& options) {
  std::vector<GraphMutation> order = {GraphMutation::kParameter, GraphMutation::kAddTask, GraphMutation::kRemoveTask,
                                      GraphMutation::kAddHook, GraphMutation::kRemoveHook};
  // Tries them in a random order until one applies: uniform among the applicable ones.
  for (std::size_t n = order.size(); n > 0; --n) {
    const std::size_t k = static_cast<std::size_t>(random.below(n));
    const GraphMutation m = order[k];
    order.erase(order.begin() + static_cast<std::ptrdiff_t>(k));
    bool done = false;
    switch (m) {
      case GraphMutation::kParameter: done = mutate_parameter(g, registry, random, options); break;
      case GraphMutation::kAddTask: done = add_task(g, registry, random, options); break;
      case GraphMutation::kRemoveTask: done = remove_task(g, random); break;
      case GraphMutation::kAddHook: done = add_hook(g, random, options); break;
      case GraphMutation::kRemoveHook: done = remove_hook(g, random); break;
    }
    if (done) return m;
  }
  return std::nullopt;
}

}  // namespace symb::evo
