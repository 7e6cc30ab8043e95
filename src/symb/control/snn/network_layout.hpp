// A grown network's layout (development.hpp's GrownNetwork: sites, classes, synapses, channel
// maps) as a flat list of numbers, so a controller task can publish it through Task::probe() like
// any other internal state, and a recorder on the far side of a sink (symb run's output folder)
// can rebuild it and draw it, without the two sharing memory or the recorder regrowing it.
//
// Encoding (every number a float, integers exact below 2^24):
//   kLayoutVersion, width, height, neurons N, synapses S, input channels I, output channels O,
//   N x (x, y, class, bias, cell id), S x (source, target, weight, delay),
//   I x (count, neurons...), O x (count, neurons...).
// The spec's neuron parameters come back from the classes (params_of); the integration scheme is
// not carried (a picture does not need it).
#pragma once

#include <span>
#include <vector>

#include "symb/control/snn/development.hpp"
#include "symb/kernel/result.hpp"

namespace symb::control::snn {

inline constexpr float kLayoutVersion = 1;

std::vector<float> layout_values(const GrownNetwork& net);
// Rebuilds the layout; errors say which field is wrong (a foreign or cut sample).
kernel::Result<GrownNetwork> layout_from_values(std::span<const float> values);

}  // namespace symb::control::snn
