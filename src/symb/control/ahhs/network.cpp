#include "symb/control/ahhs/network.hpp"

#include <algorithm>
#include <cmath>
#include <set>

namespace symb::control::ahhs {

using kernel::Error;

const char* to_string(RuleKind k) {
  switch (k) {
    case RuleKind::kSensor: return "sensor";
    case RuleKind::kHormone: return "hormone";
    case RuleKind::kNonlinear: return "nonlinear";
    case RuleKind::kActuator: return "actuator";
  }
  return "?";
}

std::size_t Network::sensor_count() const {
  std::size_t n = 0;
  for (const Placement& s : sensors) n = std::max<std::size_t>(n, s.index + 1);
  return n;
}

namespace {

bool finite(float v) { return std::isfinite(v); }

}  // namespace

kernel::Status validate(const Network& n) {
  if (n.compartments == 0 || n.compartments > kMaxCompartments)
    return Error{"compartments must be 1 to " + std::to_string(kMaxCompartments)};
  if (n.hormones.empty() || n.hormones.size() > kMaxHormones)
    return Error{"a network has 1 to " + std::to_string(kMaxHormones) + " hormones"};
  if (n.links.size() > kMaxLinks) return Error{"at most " + std::to_string(kMaxLinks) + " links"};
  if (n.rules.size() > kMaxRules) return Error{"at most " + std::to_string(kMaxRules) + " rules"};
  if (n.actuators.size() > kMaxActuators) return Error{"at most " + std::to_string(kMaxActuators) + " actuators"};

  std::vector<std::uint32_t> degree(n.compartments, 0);
  std::set<std::pair<std::uint32_t, std::uint32_t>> seen;
  for (std::size_t k = 0; k < n.links.size(); ++k) {
    auto [a, b] = n.links[k];
    const std::string at = "link " + std::to_string(a) + " " + std::to_string(b) + ": ";
    if (a >= n.compartments || b >= n.compartments)
      return Error{at + "no such compartment (there are " + std::to_string(n.compartments) + ")"};
    if (a == b) return Error{at + "a compartment cannot be its own neighbour"};
    if (!seen.insert({std::min(a, b), std::max(a, b)}).second) return Error{at + "given twice"};
    ++degree[a];
    ++degree[b];
  }
  const std::uint32_t max_degree = degree.empty() ? 0 : *std::max_element(degree.begin(), degree.end());

  std::set<std::string> names;
  for (std::size_t h = 0; h < n.hormones.size(); ++h) {
    const Hormone& x = n.hormones[h];
    const std::string at = "hormone " + (x.name.empty() ? std::to_string(h) : x.name) + ": ";
    if (!x.name.empty() && !names.insert(x.name).second) return Error{at + "name given twice"};
    if (!finite(x.base) || !finite(x.decay) || !finite(x.diffusion) || !finite(x.min) || !finite(x.max) ||
        !finite(x.start))
      return Error{at + "every number must be finite"};
    if (x.decay < 0 || x.decay > 1) return Error{at + "decay must be 0 to 1"};
    if (x.diffusion < 0 || x.diffusion > 1) return Error{at + "diffusion must be 0 to 1"};
    if (!(x.min < x.max)) return Error{at + "min must be below max"};
    if (x.start < x.min || x.start > x.max) return Error{at + "start must lie within [min, max]"};
    if (static_cast<double>(x.diffusion) * max_degree > 1.0)
      return Error{at + "diffusion " + std::to_string(x.diffusion) + " times " + std::to_string(max_degree) +
                   " neighbours exceeds 1 (a compartment would give away more than it has)"};
  }

  std::vector<bool> sensor_used(kMaxSensorIndex, false);
  for (const Placement& s : n.sensors) {
    const std::string at = "sensor " + std::to_string(s.index) + ": ";
    if (s.index >= kMaxSensorIndex) return Error{at + "index must be below " + std::to_string(kMaxSensorIndex)};
    if (s.compartment >= n.compartments) return Error{at + "no such compartment"};
    if (sensor_used[s.index]) return Error{at + "placed twice"};
    sensor_used[s.index] = true;
  }
  std::vector<bool> actuator_used(n.actuators.size(), false);
  for (const Placement& a : n.actuators) {
    const std::string at = "actuator " + std::to_string(a.index) + ": ";
    if (a.index >= n.actuators.size())
      return Error{at + "actuators are numbered 0 to " + std::to_string(n.actuators.size() - 1)};
    if (a.compartment >= n.compartments) return Error{at + "no such compartment"};
    if (actuator_used[a.index]) return Error{at + "placed twice"};
    actuator_used[a.index] = true;
  }

  for (std::size_t k = 0; k < n.rules.size(); ++k) {
    const Rule& r = n.rules[k];
    const std::string at = "rule " + std::to_string(k) + " (" + to_string(r.kind) + "): ";
    if (!finite(r.centre) || !finite(r.width) || !finite(r.fixed) || !finite(r.dependent))
      return Error{at + "every number must be finite"};
    if (!(r.width > 0)) return Error{at + "width must be above 0"};
    if (r.kind == RuleKind::kSensor) {
      if (r.source >= kMaxSensorIndex || !sensor_used[r.source]) return Error{at + "reads a sensor not placed"};
    } else if (r.source >= n.hormones.size()) {
      return Error{at + "reads no such hormone"};
    }
    if (r.kind == RuleKind::kActuator) {
      if (r.target >= n.actuators.size()) return Error{at + "drives no such actuator"};
    } else if (r.target >= n.hormones.size()) {
      return Error{at + "changes no such hormone"};
    }
    if (r.compartment != kEveryCompartment) {
      if (r.kind == RuleKind::kSensor || r.kind == RuleKind::kActuator)
        return Error{at + "runs where its sensor or actuator sits; it takes no compartment"};
      if (r.compartment < 0 || static_cast<std::uint32_t>(r.compartment) >= n.compartments)
        return Error{at + "no such compartment"};
    }
  }
  return {};
}

std::vector<std::vector<std::uint32_t>> neighbour_lists(const Network& n) {
  std::vector<std::vector<std::uint32_t>> out(n.compartments);
  for (auto [a, b] : n.links) {
    if (a >= n.compartments || b >= n.compartments) continue;
    out[a].push_back(b);
    out[b].push_back(a);
  }
  for (auto& l : out) std::sort(l.begin(), l.end());
  return out;
}

}  // namespace symb::control::ahhs
