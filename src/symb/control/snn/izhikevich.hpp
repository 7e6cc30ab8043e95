// Izhikevich neurons (Izhikevich 2003, IEEE TNN 14:1569): a two-variable model that reproduces
// the firing patterns of cortical neurons at about the cost of an integrate-and-fire neuron,
//
//   v' = 0.04 v^2 + 5 v + 140 - u + I,   u' = a (b v - u),   if v >= 30 mV: v <- c, u <- u + d,
//
// with time in ms. The seven standard classes of the paper's Fig. 2 are named parameter sets.
// Two integration schemes for the fixed 1 ms step:
//  - kPublished: the 2003 paper's net.m: v takes two half steps of 0.5 ms, then u one 1 ms step
//    from the NEW v (NEST's consistent_integration=false; needed to reproduce published results);
//  - kEuler: plain forward Euler of both variables from the old values over 1 ms (NEST's default).
// In both, a neuron fires at the START of the step in which v >= 30 (net.m's order): it is reset,
// and then integrated with the step's input.
#pragma once

#include <cstdint>
#include <string_view>

#include "symb/kernel/result.hpp"

namespace symb::control::snn {

enum class NeuronClass : std::uint8_t { kRS, kIB, kCH, kFS, kLTS, kTC, kRZ };
inline constexpr int kNeuronClassCount = 7;

struct NeuronParams {
  float a = 0.02f, b = 0.2f, c = -65.0f, d = 8.0f;
  bool operator==(const NeuronParams&) const = default;
};

enum class Integration : std::uint8_t { kPublished, kEuler };

inline constexpr float kPeakVoltage = 30.0f;   // mV: v >= this is a spike
inline constexpr float kRestVoltage = -65.0f;  // mV: initial v; initial u = b v

// The class's a, b, c, d (Fig. 2 of the 2003 paper; controller-models.md 3.2).
NeuronParams params_of(NeuronClass c);
// "RS", "IB", "CH", "FS", "LTS", "TC", "RZ".
const char* to_string(NeuronClass c);
// Exact upper-case names as above; the error lists them.
kernel::Result<NeuronClass> parse_neuron_class(std::string_view name);
// "published" or "euler".
const char* to_string(Integration i);
kernel::Result<Integration> parse_integration(std::string_view name);

// One neuron's state; the network keeps these in arrays (spiking_network.hpp), this is the scalar
// reference the tests and the single-neuron golden file use.
struct NeuronState {
  float v = kRestVoltage;
  float u = 0;
};

// One 1 ms step of one neuron with input current `current`: returns whether it fired at the start
// of the step (and was reset before integrating). The network's vector loop computes exactly this.
bool step_neuron(NeuronState& s, const NeuronParams& p, float current, Integration scheme);

}  // namespace symb::control::snn
