// The reference network of Izhikevich 2003 (net.m; controller-models.md 3.3), a built-in example:
// 800 excitatory neurons (a = 0.02, b = 0.2, c = -65 + 15 r^2, d = 8 - 6 r^2) and 200 inhibitory
// ones (a = 0.02 + 0.08 r, b = 0.25 - 0.05 r, c = -65, d = 2), r ~ U[0, 1) per neuron; all-to-all
// synapses of weight 0.5 U[0, 1) from excitatory and -U[0, 1) from inhibitory neurons, delay 0
// (net.m has no self-exclusion: neuron j also projects onto itself); the published integration
// scheme. Each step gets "thalamic" input 5 N(0, 1) (excitatory) or 2 N(0, 1) (inhibitory).
//
// Everything random comes from the stream passed in, in a documented order (r for all neurons in
// index order, then the weight matrix row by row of source neurons, then per step the thalamic
// input in neuron order), so the same seed gives the same raster bit for bit.
#pragma once

#include <cstddef>
#include <span>

#include "symb/control/snn/spiking_network.hpp"
#include "symb/kernel/random_stream.hpp"

namespace symb::control::snn {

struct ReferenceNetworkSize {
  std::size_t excitatory = 800;
  std::size_t inhibitory = 200;
};

NetworkSpec reference_network(kernel::RandomStream& random, ReferenceNetworkSize size = {});

// Adds one step's thalamic input into `input` (the network's input()): the first `excitatory`
// neurons get 5 N(0, 1), the rest 2 N(0, 1).
void add_thalamic_input(kernel::RandomStream& random, std::span<float> input, std::size_t excitatory);

}  // namespace symb::control::snn
