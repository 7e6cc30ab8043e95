#include "symb/control/snn/izhikevich.hpp"

#include <string>

namespace symb::control::snn {

namespace {

struct ClassEntry {
  const char* name;
  NeuronParams params;
};

// Fig. 2 of Izhikevich 2003 (controller-models.md 3.2), in NeuronClass order.
constexpr ClassEntry kClasses[kNeuronClassCount] = {
    {"RS", {0.02f, 0.2f, -65.0f, 8.0f}}, {"IB", {0.02f, 0.2f, -55.0f, 4.0f}},   {"CH", {0.02f, 0.2f, -50.0f, 2.0f}},
    {"FS", {0.1f, 0.2f, -65.0f, 2.0f}},  {"LTS", {0.02f, 0.25f, -65.0f, 2.0f}}, {"TC", {0.02f, 0.25f, -65.0f, 0.05f}},
    {"RZ", {0.1f, 0.26f, -65.0f, 2.0f}},
};

std::string class_names() {
  std::string out;
  for (const ClassEntry& e : kClasses) {
    if (!out.empty()) out += ", ";
    out += e.name;
  }
  return out;
}

}  // namespace

NeuronParams params_of(NeuronClass c) {
  const auto i = static_cast<std::size_t>(c);
  return i < kNeuronClassCount ? kClasses[i].params : NeuronParams{};
}

const char* to_string(NeuronClass c) {
  const auto i = static_cast<std::size_t>(c);
  return i < kNeuronClassCount ? kClasses[i].name : "?";
}

kernel::Result<NeuronClass> parse_neuron_class(std::string_view name) {
  for (int i = 0; i < kNeuronClassCount; ++i)
    if (name == kClasses[i].name) return static_cast<NeuronClass>(i);
  return kernel::Error{"unknown neuron class '" + std::string(name) + "' (valid: " + class_names() + ")"};
}

const char* to_string(Integration i) {
  switch (i) {
    case Integration::kPublished: return "published";
    case Integration::kEuler: return "euler";
  }
  return "?";
}

kernel::Result<Integration> parse_integration(std::string_view name) {
  if (name == "published") return Integration::kPublished;
  if (name == "euler") return Integration::kEuler;
  return kernel::Error{"unknown integration scheme '" + std::string(name) + "' (valid: published, euler)"};
}

bool step_neuron(NeuronState& s, const NeuronParams& p, float current, Integration scheme) {
  const bool fired = s.v >= kPeakVoltage;
  if (fired) {
    s.v = p.c;
    s.u = s.u + p.d;
  }
  // The same expressions, in the same order, as SpikingNetwork::step()'s vector loop: the tests
  // require bit-identical states. 0.04 (v*v) as net.m's 0.04*v.^2.
  const float v = s.v, u = s.u;
  if (scheme == Integration::kPublished) {
    const float v1 = v + 0.5f * (0.04f * (v * v) + 5.0f * v + 140.0f - u + current);
    const float v2 = v1 + 0.5f * (0.04f * (v1 * v1) + 5.0f * v1 + 140.0f - u + current);
    s.v = v2;
    s.u = u + p.a * (p.b * v2 - u);
  } else {
    s.v = v + (0.04f * (v * v) + 5.0f * v + 140.0f - u + current);
    s.u = u + p.a * (p.b * v - u);
  }
  return fired;
}

}  // namespace symb::control::snn
