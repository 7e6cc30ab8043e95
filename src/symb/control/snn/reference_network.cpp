#include "symb/control/snn/reference_network.hpp"

namespace symb::control::snn {

NetworkSpec reference_network(kernel::RandomStream& random, ReferenceNetworkSize size) {
  const std::size_t ne = size.excitatory, n = size.excitatory + size.inhibitory;
  NetworkSpec spec;
  spec.integration = Integration::kPublished;
  spec.neurons.reserve(n);
  // Parameters in double as MATLAB computes them, then rounded once to the network's float.
  for (std::size_t i = 0; i < n; ++i) {
    const double r = random.uniform();
    NeuronParams p;
    if (i < ne) {
      p = {0.02f, 0.2f, static_cast<float>(-65.0 + 15.0 * r * r), static_cast<float>(8.0 - 6.0 * r * r)};
    } else {
      p = {static_cast<float>(0.02 + 0.08 * r), static_cast<float>(0.25 - 0.05 * r), -65.0f, 2.0f};
    }
    spec.neurons.push_back(p);
  }
  // net.m's S(target, source): drawn row by row of sources here, so each source's row is one run.
  spec.synapses.reserve(n * n);
  for (std::size_t j = 0; j < n; ++j) {
    const bool excitatory = j < ne;
    for (std::size_t i = 0; i < n; ++i) {
      const double w = excitatory ? 0.5 * random.uniform() : -random.uniform();
      spec.synapses.push_back({static_cast<std::uint32_t>(j), static_cast<std::uint32_t>(i), static_cast<float>(w), 0});
    }
  }
  return spec;
}

void add_thalamic_input(kernel::RandomStream& random, std::span<float> input, std::size_t excitatory) {
  for (std::size_t i = 0; i < input.size(); ++i) {
    const double scale = i < excitatory ? 5.0 : 2.0;
    input[i] += static_cast<float>(scale * random.normal());
  }
}

}  // namespace symb::control::snn
