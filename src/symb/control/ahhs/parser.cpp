#include "symb/control/ahhs/parser.hpp"

#include <charconv>
#include <cmath>
#include <map>
#include <optional>
#include <vector>

#include "symb/kernel/source_text.hpp"

namespace symb::control::ahhs {

using kernel::Error;

namespace {

using Token = kernel::TextToken;

class Parser {
 public:
  explicit Parser(std::string_view text) : text_(text) {}

  kernel::Result<Network> run() {
    if (text_.size() > kMaxDescriptionBytes)
      return kernel::located_error({1, 1},
                                   "description longer than " + std::to_string(kMaxDescriptionBytes) + " bytes");
    // Statements end at a line's end or a ';'.
    auto st = kernel::for_each_line(text_, [&](std::string_view line, std::size_t number) -> kernel::Status {
      auto words = kernel::split_words(line, number, ";");
      if (!words) return Error{words.error()};
      std::size_t first = 0;
      for (std::size_t k = 0; k <= words->size(); ++k) {
        if (k < words->size() && (*words)[k].text != ";") continue;
        if (k > first)
          if (auto done = parse_statement({words->begin() + static_cast<std::ptrdiff_t>(first),
                                           words->begin() + static_cast<std::ptrdiff_t>(k)});
              !done)
            return done;
        first = k + 1;
      }
      end_ = {std::string_view(), number, line.size() + 1};
      return {};
    });
    if (!st) return Error{st.error()};
    return complete();
  }

 private:
  kernel::Status parse_statement(const std::vector<Token>& s) {
    const std::string_view kw = s[0].text;
    if (kw != "compartments" && !have_compartments_)
      return s[0].error("declare the compartments first (compartments N)");
    if (kw == "compartments") return compartments(s);
    if (kw == "link") return link(s);
    if (kw == "hormone") return hormone(s);
    if (kw == "sensor" || kw == "actuator") return placement(s);
    if (kw == "rule") return rule(s);
    return s[0].error("unknown statement '" + std::string(kw) +
                      "' (compartments, link, hormone, sensor, actuator or rule)");
  }

  kernel::Result<std::uint64_t> integer(const Token& t, std::uint64_t max, const char* what) {
    std::uint64_t v = 0;
    auto [p, ec] = std::from_chars(t.text.data(), t.text.data() + t.text.size(), v);
    if (ec != std::errc() || p != t.text.data() + t.text.size())
      return t.error(std::string(what) + " must be a whole number, got '" + std::string(t.text) + "'");
    if (v > max) return t.error(std::string(what) + " must be at most " + std::to_string(max));
    return v;
  }

  kernel::Result<float> real(const Token& t, const char* what) {
    float v = 0;
    auto [p, ec] = std::from_chars(t.text.data(), t.text.data() + t.text.size(), v);
    if (ec != std::errc() || p != t.text.data() + t.text.size() || !std::isfinite(v))
      return t.error(std::string(what) + " must be a finite number, got '" + std::string(t.text) + "'");
    return v;
  }

  kernel::Result<std::uint32_t> compartment(const Token& t) {
    auto v = integer(t, net_.compartments - 1, "a compartment");
    if (!v) return Error{v.error()};
    return static_cast<std::uint32_t>(*v);
  }

  kernel::Result<std::uint32_t> hormone_ref(const Token& t) {
    auto it = hormone_ids_.find(std::string(t.text));
    if (it == hormone_ids_.end()) return t.error("no hormone named '" + std::string(t.text) + "' declared above");
    return it->second;
  }

  kernel::Status arity(const std::vector<Token>& s, std::size_t n, const char* shape) {
    if (s.size() < n) {
      const Token& last = s.back();
      return last.error_after(std::string("incomplete: ") + shape);
    }
    if (s.size() > n) return s[n].error(std::string("unexpected '") + std::string(s[n].text) + "': " + shape);
    return {};
  }

  kernel::Status compartments(const std::vector<Token>& s) {
    if (have_compartments_) return s[0].error("compartments declared twice");
    if (auto st = arity(s, 2, "compartments N"); !st) return st;
    auto n = integer(s[1], kMaxCompartments, "the number of compartments");
    if (!n) return Error{n.error()};
    if (*n == 0) return s[1].error("a network has at least one compartment");
    net_.compartments = static_cast<std::uint32_t>(*n);
    have_compartments_ = true;
    degree_.assign(net_.compartments, 0);
    return {};
  }

  kernel::Status link(const std::vector<Token>& s) {
    if (auto st = arity(s, 3, "link A B"); !st) return st;
    auto a = compartment(s[1]);
    if (!a) return Error{a.error()};
    auto b = compartment(s[2]);
    if (!b) return Error{b.error()};
    if (*a == *b) return s[2].error("a compartment cannot be its own neighbour");
    if (net_.links.size() >= kMaxLinks) return s[0].error("more than " + std::to_string(kMaxLinks) + " links");
    const auto key = std::make_pair(std::min(*a, *b), std::max(*a, *b));
    if (!links_.emplace(key, s[0]).second) return s[0].error("this link is given twice");
    net_.links.push_back({*a, *b});
    ++degree_[*a];
    ++degree_[*b];
    return {};
  }

  // KEY VALUE pairs from s[first] on; `allowed` lists the keys, every one at most once.
  kernel::Result<std::map<std::string, std::pair<float, Token>>> pairs(const std::vector<Token>& s, std::size_t first,
                                                                       std::initializer_list<const char*> allowed) {
    std::map<std::string, std::pair<float, Token>> out;
    for (std::size_t k = first; k < s.size(); k += 2) {
      const std::string key(s[k].text);
      bool known = false;
      std::string list;
      for (const char* a : allowed) {
        known = known || key == a;
        list += (list.empty() ? "" : ", ") + std::string(a);
      }
      if (!known) return s[k].error("unknown key '" + key + "' (expected " + list + ")");
      if (out.count(key) != 0) return s[k].error("'" + key + "' given twice");
      if (k + 1 >= s.size()) return s[k].error_after("'" + key + "' needs a value");
      if (key == "in") {
        auto c = compartment(s[k + 1]);
        if (!c) return Error{c.error()};
        out[key] = {static_cast<float>(*c), s[k + 1]};
        continue;
      }
      auto v = real(s[k + 1], ("'" + key + "'").c_str());
      if (!v) return Error{v.error()};
      out[key] = {*v, s[k + 1]};
    }
    return out;
  }

  kernel::Status hormone(const std::vector<Token>& s) {
    if (s.size() < 2) return arity(s, 2, "hormone NAME base X decay X diffusion X");
    if (!kernel::is_identifier(s[1].text, 64))
      return s[1].error("a hormone name is a letter or '_', then letters, digits or '_'");
    if (hormone_ids_.count(std::string(s[1].text)) != 0)
      return s[1].error("hormone '" + std::string(s[1].text) + "' declared twice");
    if (net_.hormones.size() >= kMaxHormones)
      return s[0].error("at most " + std::to_string(kMaxHormones) +
                        " hormones (one message carries a compartment's levels)");
    auto kv = pairs(s, 2, {"base", "decay", "diffusion", "min", "max", "start"});
    if (!kv) return Error{kv.error()};
    Hormone h;
    h.name = std::string(s[1].text);
    auto get = [&](const char* k, float& v) {
      if (auto it = kv->find(k); it != kv->end()) v = it->second.first;
    };
    get("base", h.base);
    get("decay", h.decay);
    get("diffusion", h.diffusion);
    get("min", h.min);
    get("max", h.max);
    h.start = h.min;
    get("start", h.start);
    auto at = [&](const char* k) { return kv->count(k) ? kv->at(k).second : s[1]; };
    if (h.decay < 0 || h.decay > 1) return at("decay").error("decay must be 0 to 1");
    if (h.diffusion < 0 || h.diffusion > 1) return at("diffusion").error("diffusion must be 0 to 1");
    if (!(h.min < h.max)) return at("max").error("max must be above min");
    if (h.start < h.min || h.start > h.max) return at("start").error("start must lie within [min, max]");
    hormone_ids_[h.name] = static_cast<std::uint32_t>(net_.hormones.size());
    hormone_at_.push_back(at("diffusion"));
    net_.hormones.push_back(std::move(h));
    return {};
  }

  kernel::Status placement(const std::vector<Token>& s) {
    const bool sensor = s[0].text == "sensor";
    if (auto st = arity(s, 4, sensor ? "sensor INDEX in COMPARTMENT" : "actuator INDEX in COMPARTMENT"); !st) return st;
    auto index =
        integer(s[1], (sensor ? kMaxSensorIndex : kMaxActuators) - 1, sensor ? "a sensor index" : "an actuator index");
    if (!index) return Error{index.error()};
    if (s[2].text != "in") return s[2].error("expected 'in'");
    auto c = compartment(s[3]);
    if (!c) return Error{c.error()};
    auto& list = sensor ? net_.sensors : net_.actuators;
    for (const Placement& p : list)
      if (p.index == *index)
        return s[1].error(std::string(sensor ? "sensor " : "actuator ") + std::string(s[1].text) + " placed twice");
    list.push_back({static_cast<std::uint32_t>(*index), *c});
    if (!sensor) actuator_at_.push_back(s[1]);
    return {};
  }

  kernel::Status rule(const std::vector<Token>& s) {
    const char* shape = "rule KIND SOURCE -> TARGET centre X width X [fixed X] [dependent X] [in C]";
    if (s.size() < 5) return arity(s, 5, shape);
    Rule r;
    const std::string_view kind = s[1].text;
    if (kind == "sensor")
      r.kind = RuleKind::kSensor;
    else if (kind == "hormone")
      r.kind = RuleKind::kHormone;
    else if (kind == "nonlinear")
      r.kind = RuleKind::kNonlinear;
    else if (kind == "actuator")
      r.kind = RuleKind::kActuator;
    else
      return s[1].error("unknown rule kind '" + std::string(kind) + "' (sensor, hormone, nonlinear or actuator)");
    if (s[3].text != "->") return s[3].error("expected '->'");
    if (r.kind == RuleKind::kSensor) {
      auto i = integer(s[2], kMaxSensorIndex - 1, "a sensor index");
      if (!i) return Error{i.error()};
      bool placed = false;
      for (const Placement& p : net_.sensors) placed = placed || p.index == *i;
      if (!placed) return s[2].error("sensor " + std::string(s[2].text) + " is not placed (sensor INDEX in C) above");
      r.source = static_cast<std::uint32_t>(*i);
    } else {
      auto h = hormone_ref(s[2]);
      if (!h) return Error{h.error()};
      r.source = *h;
    }
    if (r.kind == RuleKind::kActuator) {
      auto i = integer(s[4], kMaxActuators - 1, "an actuator index");
      if (!i) return Error{i.error()};
      bool placed = false;
      for (const Placement& p : net_.actuators) placed = placed || p.index == *i;
      if (!placed)
        return s[4].error("actuator " + std::string(s[4].text) + " is not placed (actuator INDEX in C) above");
      r.target = static_cast<std::uint32_t>(*i);
    } else {
      auto h = hormone_ref(s[4]);
      if (!h) return Error{h.error()};
      r.target = *h;
    }
    const bool placed_rule = r.kind == RuleKind::kSensor || r.kind == RuleKind::kActuator;
    auto kv = placed_rule ? pairs(s, 5, {"centre", "width", "fixed", "dependent"})
                          : pairs(s, 5, {"centre", "width", "fixed", "dependent", "in"});
    if (!kv) return Error{kv.error()};
    if (!kv->count("centre")) return s[0].error("the rule needs 'centre X'");
    if (!kv->count("width")) return s[0].error("the rule needs 'width X'");
    r.centre = kv->at("centre").first;
    r.width = kv->at("width").first;
    if (!(r.width > 0))
      return (kv->at("width").second).error("width must be above 0 (a window of width 0 never fires)");
    if (kv->count("fixed")) r.fixed = kv->at("fixed").first;
    if (kv->count("dependent")) r.dependent = kv->at("dependent").first;
    if (kv->count("in")) r.compartment = static_cast<std::int32_t>(kv->at("in").first);
    if (net_.rules.size() >= kMaxRules) return s[0].error("more than " + std::to_string(kMaxRules) + " rules");
    net_.rules.push_back(r);
    return {};
  }

  kernel::Result<Network> complete() {
    if (!have_compartments_) return end_.error("empty description: declare compartments, hormones and rules");
    if (net_.hormones.empty()) return end_.error("declare at least one hormone");
    std::uint32_t max_degree = 0;
    for (std::uint32_t d : degree_) max_degree = std::max(max_degree, d);
    for (std::size_t h = 0; h < net_.hormones.size(); ++h)
      if (static_cast<double>(net_.hormones[h].diffusion) * max_degree > 1.0)
        return hormone_at_[h].error("diffusion times the largest number of neighbours (" + std::to_string(max_degree) +
                                    ") exceeds 1");
    for (std::size_t k = 0; k < net_.actuators.size(); ++k)
      if (net_.actuators[k].index >= net_.actuators.size())
        return actuator_at_[k].error("actuators are numbered 0 to " + std::to_string(net_.actuators.size() - 1) +
                                     " without gaps");
    if (auto st = validate(net_); !st) return end_.error(st.error());
    return std::move(net_);
  }

  std::string_view text_;
  Network net_;
  bool have_compartments_ = false;
  std::vector<std::uint32_t> degree_;
  std::map<std::pair<std::uint32_t, std::uint32_t>, Token> links_;
  std::map<std::string, std::uint32_t> hormone_ids_;
  std::vector<Token> hormone_at_;
  std::vector<Token> actuator_at_;
  Token end_;
};

}  // namespace

kernel::Result<Network> parse_network(std::string_view text) { return Parser(text).run(); }

std::string to_text(const Network& n) {
  std::string out = "compartments " + std::to_string(n.compartments) + "\n";
  for (auto [a, b] : n.links) out += "link " + std::to_string(a) + " " + std::to_string(b) + "\n";
  for (std::size_t h = 0; h < n.hormones.size(); ++h) {
    const Hormone& x = n.hormones[h];
    const std::string name = x.name.empty() ? "h" + std::to_string(h) : x.name;
    out += "hormone " + name + " base " + kernel::shortest_text<float>(x.base) + " decay " +
           kernel::shortest_text<float>(x.decay) + " diffusion " + kernel::shortest_text<float>(x.diffusion) + " min " +
           kernel::shortest_text<float>(x.min) + " max " + kernel::shortest_text<float>(x.max) + " start " +
           kernel::shortest_text<float>(x.start) + "\n";
  }
  for (const Placement& s : n.sensors)
    out += "sensor " + std::to_string(s.index) + " in " + std::to_string(s.compartment) + "\n";
  for (const Placement& a : n.actuators)
    out += "actuator " + std::to_string(a.index) + " in " + std::to_string(a.compartment) + "\n";
  auto hname = [&](std::uint32_t h) {
    return h < n.hormones.size() && !n.hormones[h].name.empty() ? n.hormones[h].name : "h" + std::to_string(h);
  };
  for (const Rule& r : n.rules) {
    out += std::string("rule ") + to_string(r.kind) + " ";
    out += r.kind == RuleKind::kSensor ? std::to_string(r.source) : hname(r.source);
    out += " -> ";
    out += r.kind == RuleKind::kActuator ? std::to_string(r.target) : hname(r.target);
    out += " centre " + kernel::shortest_text<float>(r.centre) + " width " + kernel::shortest_text<float>(r.width) +
           " fixed " + kernel::shortest_text<float>(r.fixed) + " dependent " +
           kernel::shortest_text<float>(r.dependent);
    if (r.compartment != kEveryCompartment) out += " in " + std::to_string(r.compartment);
    out += "\n";
  }
  return out;
}

}  // namespace symb::control::ahhs
