// Network descriptions: the small text format that names a network's topology, weights and
// scaling in one file (docs/networks.md), and weight lists (a flat list of numbers, the genome).
// One key a line, `#` starts a comment, a list may continue on the lines after its key:
//
//   type mlp              # mlp | elman | ctrnn
//   inputs 7
//   layers 2              # hidden layer sizes then the output size; ctrnn: N O
//   activation tanh       # tanh | sigmoid | linear (mlp, elman)
//   input_scale 0.000222  # one factor, or one per input
//   output_scale 500
//   tau 0.1               # ctrnn: time constants in seconds, one or one per neuron
//   weights               # exactly genome-size numbers (network.hpp gives the order)
//     0.5 0.4 ...
//
// Every error starts with LINE:COLUMN of the offending text; nothing is read past the text.
#pragma once

#include <cstddef>
#include <optional>
#include <string_view>
#include <vector>

#include "symb/control/network/network.hpp"
#include "symb/kernel/result.hpp"

namespace symb::control::network {

struct Description {
  Topology topology;
  std::optional<std::vector<float>> weights;  // absent: the network starts with zero weights
  std::vector<float> input_scale;             // empty: not given
  std::optional<double> output_scale;
  std::vector<float> tau;  // empty: not given
};

// Parses and checks a description: every key known and given once, type and layers present,
// counts matching the topology. Errors: "LINE:COLUMN: message".
kernel::Result<Description> parse_description(std::string_view text);

// Parses a whitespace-separated list of finite numbers (with `#` comments), at most `max_count`
// of them. Errors: "LINE:COLUMN: message".
kernel::Result<std::vector<float>> parse_numbers(std::string_view text, std::size_t max_count = kMaxGenome);

}  // namespace symb::control::network
