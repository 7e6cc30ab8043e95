// Network: the description of an Artificial Homeostatic Hormone System (AHHS; Schmickl, Hamann,
// Crailsheim 2011): compartments joined by neighbour links, hormones (each with base emission,
// decay and diffusion), sensors and actuators placed in compartments, and rules. A rule reads one
// value (a sensor, or a hormone of the compartment it runs in), passes it through a triangular
// trigger window and adds a dose (fixed + dependent * value) to a hormone's change or to an
// actuator. The network is plain data: the model (model.hpp) compiles it for stepping, the text
// format (parser.hpp, docs/ahhs.md) writes it down, mutation.hpp changes it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "symb/kernel/result.hpp"

namespace symb::control::ahhs {

// Bounds that keep every network small enough for a message and a microcontroller.
inline constexpr std::size_t kMaxHormones = 31;     // [compartment id, h0..h30] fills one message
inline constexpr std::size_t kMaxSensorIndex = 32;  // sensor vectors travel in one message
inline constexpr std::size_t kMaxActuators = 32;    // the actuator vector travels in one message
inline constexpr std::size_t kMaxCompartments = 100000;
inline constexpr std::size_t kMaxRules = 100000;
inline constexpr std::size_t kMaxLinks = 400000;

struct Hormone {
  std::string name;
  float base = 0;       // emission per step, in every compartment
  float decay = 0;      // share lost per step, 0..1
  float diffusion = 0;  // share exchanged per step with each neighbour; diffusion * degree <= 1
  float min = 0, max = 1;
  float start = 0;  // level at step 0, within [min, max]

  bool operator==(const Hormone&) const = default;
};

enum class RuleKind : std::uint8_t {
  kSensor,     // sensor -> hormone:    dH[o] += tau(s) * (dependent * s + fixed)
  kHormone,    // hormone -> hormone:   dH[o] += tau(H[i]) * (dependent * H[i] + fixed)
  kNonlinear,  // hormone -> hormone:   dH[o] += tau(H[i]) * (dependent * H[i] * H[o] + fixed)
  kActuator,   // hormone -> actuator:  A[o]  += tau(H[i]) * (dependent * H[i] + fixed)
};
const char* to_string(RuleKind k);

inline constexpr std::int32_t kEveryCompartment = -1;

struct Rule {
  RuleKind kind = RuleKind::kHormone;
  std::uint32_t source = 0;  // sensor index (kSensor) or hormone index
  std::uint32_t target = 0;  // hormone index, or actuator index (kActuator)
  float centre = 0;
  float width = 1;  // > 0: the trigger window is (centre - width, centre + width)
  float fixed = 0;
  float dependent = 0;
  // Hormone and nonlinear rules: the compartment they run in, or every compartment. Sensor and
  // actuator rules run where their sensor or actuator sits.
  std::int32_t compartment = kEveryCompartment;

  bool operator==(const Rule&) const = default;
};

// The triangular trigger: 1 at the centre, falling linearly to 0 at centre +- width, 0 outside.
// Continuous, so "strictly inside" and "inside or on the edge" give the same value (0 on the edge).
inline float trigger(float x, float centre, float width) {
  const float d = x < centre ? centre - x : x - centre;
  return d < width ? (width - d) / width : 0.0f;
}

struct Placement {
  std::uint32_t index = 0;        // position in the sensor vector, or in the actuator vector
  std::uint32_t compartment = 0;  // where it sits

  bool operator==(const Placement&) const = default;
};

struct Network {
  std::uint32_t compartments = 1;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> links;  // undirected neighbour pairs
  std::vector<Hormone> hormones;
  std::vector<Placement> sensors;
  std::vector<Placement> actuators;  // indices 0..n-1, each once
  std::vector<Rule> rules;

  // The sensor vector must be at least this long (the highest sensor index + 1).
  std::size_t sensor_count() const;
  std::size_t actuator_count() const { return actuators.size(); }
  bool operator==(const Network&) const = default;
};

// Everything a network must satisfy before it runs (indices in range, windows > 0, bounds ordered,
// diffusion * degree <= 1 so that diffusion cannot push a level out of its bounds, no link twice,
// no self link, each sensor and actuator placed once, actuator indices 0..n-1, the limits above).
// The error names the offending item ("rule 3: ...").
kernel::Status validate(const Network& n);

// Neighbours of every compartment, each list sorted ascending (the order diffusion sums in).
std::vector<std::vector<std::uint32_t>> neighbour_lists(const Network& n);

}  // namespace symb::control::ahhs
