// SpikingNetwork: a network of Izhikevich neurons (izhikevich.hpp) with weighted synapses of
// integer delays, stepped in 1 ms steps. A spike is an instantaneous current pulse: a synapse of
// weight w and delay k adds w to its target's input current in the step k ms after the spike
// (k = 0: in the same step, before integration, exactly as the 2003 paper's net.m does).
//
// Layout for speed (bench_snn): neuron state in flat arrays (structure of arrays) so the update
// loop vectorises; synapses in compressed rows by source (one contiguous run per neuron); pending
// currents in a ring of (kMaxDelay + 1) current vectors, one per future ms.
//
// Per step, in this order (net.m): (1) every neuron with v >= 30 fires and is reset (v <- c,
// u <- u + d); (2) fired neurons' synapses deliver their pulses to the ring slot of step t + delay;
// (3) I = bias + external input + the ring slot of step t; (4) v and u are integrated with I by the
// network's scheme; (5) the external input and the used ring slot are cleared.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "symb/control/snn/izhikevich.hpp"
#include "symb/kernel/result.hpp"

namespace symb::control::snn {

inline constexpr std::uint32_t kMaxDelay = 63;        // ms
inline constexpr std::size_t kMaxNeurons = 1u << 24;  // fits the AER neuron field (aer.hpp)
inline constexpr float kMaxAbsWeight = 1000.0f;       // a pulse larger than this is an error
inline constexpr float kMaxAbsBias = 1000.0f;

struct Synapse {
  std::uint32_t source = 0;
  std::uint32_t target = 0;
  float weight = 0;         // current pulse (the 2003 net: 0.5 U[0,1] excitatory, -U[0,1] inhibitory)
  std::uint32_t delay = 0;  // ms, 0..kMaxDelay
  bool operator==(const Synapse&) const = default;
};

// What a network is made of: built by hand, by reference_network.hpp, or grown by development.hpp.
struct NetworkSpec {
  std::vector<NeuronParams> neurons;
  std::vector<float> bias;        // tonic input current per neuron; empty: all 0
  std::vector<Synapse> synapses;  // any order; kept in this order within a source's row
  Integration integration = Integration::kPublished;
};

class SpikingNetwork {
 public:
  // Checks sizes (1..kMaxNeurons neurons, bias empty or one per neuron), every number finite and
  // within its limit, synapse ends in range, delays <= kMaxDelay. Errors name the offending index.
  static kernel::Result<SpikingNetwork> create(const NetworkSpec& spec);

  std::size_t size() const { return v_.size(); }
  std::size_t synapse_count() const { return targets_.size(); }
  Integration integration() const { return integration_; }
  // Completed steps since creation or reset(): the step about to run is step time_ms().
  std::uint64_t time_ms() const { return time_ms_; }

  // External input current for the NEXT step only (one value per neuron, added to the bias and the
  // synaptic pulses); step() clears it. Callers add into it: input()[i] += current.
  std::span<float> input() { return input_; }
  // Runs one 1 ms step; returns the neurons that fired at its start, ascending. The span is valid
  // until the next call.
  std::span<const std::uint32_t> step();

  std::span<const float> v() const { return v_; }
  std::span<const float> u() const { return u_; }
  std::span<const float> bias() const { return bias_; }
  NeuronParams params(std::uint32_t neuron) const;
  // Outgoing synapses of `source`, in spec order (targets, weights, delays of its row).
  std::vector<Synapse> synapses_of(std::uint32_t source) const;
  // All synapses, by source then spec order: a NetworkSpec built from this and the parameters
  // creates an equal network.
  NetworkSpec spec() const;

  // Back to v = -65, u = b v, no pending pulses, no input, time 0.
  void reset();

 private:
  SpikingNetwork() = default;

  Integration integration_ = Integration::kPublished;
  std::uint64_t time_ms_ = 0;
  std::vector<float> a_, b_, c_, d_, v_, u_, bias_, input_;
  std::vector<std::uint32_t> row_start_;  // size()+1 offsets into the synapse arrays
  std::vector<std::uint32_t> targets_;
  std::vector<float> weights_;
  std::vector<std::uint8_t> delays_;
  std::vector<float> ring_;  // (kMaxDelay + 1) slots of size() currents
  std::vector<std::uint32_t> fired_;
};

}  // namespace symb::control::snn
