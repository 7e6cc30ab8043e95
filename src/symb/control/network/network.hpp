// Network: the neural-network controllers' model (paper section III-C, "artificial neural networks
// of different kinds"), free of any task or time: a fixed topology plus a flat weight vector, the
// genome, which evolution (issue 7) writes and reads as a whole. Three kinds:
//
//  - mlp    feed-forward perceptron / multilayer perceptron, o = f(W x + b) layer by layer;
//  - elman  like mlp, but the first hidden layer also sees its own activations of the previous
//           step (the context units), h(t) = f(W x(t) + U h(t-1) + b);
//  - ctrnn  continuous-time recurrent network (Beer 1995):
//             tau_i dy_i/dt = -y_i + sum_j w_ji sigma(y_j + theta_j) + I_i,  I_i = sum_k v_ik x_k,
//           integrated with one Euler step of `dt` per step(); its outputs are the firing rates
//           sigma(y_i + theta_i) of the last `outputs` neurons.
//
// Genome order (fixed; docs/networks.md):
//  - mlp: layer by layer from the input side; per neuron its weights from every neuron of the
//    layer below (in order), then its bias. Size sum_l (n_{l-1} + 1) n_l.
//  - elman: the first hidden layer per neuron: weights from the inputs, weights from the context
//    units (h_0 .. h_{H-1}), then the bias; later layers as mlp.
//  - ctrnn: per neuron i: weights v_i0 .. v_i(n_in-1) from the inputs, weights w_0i .. w_(N-1)i
//    from every neuron (itself included), then the bias theta_i. Size N (n_in + N + 1). The time
//    constants are not in the genome (they are a parameter).
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "symb/kernel/result.hpp"

namespace symb::control::network {

enum class Kind { kMlp, kElman, kCtrnn };
enum class Activation { kTanh, kSigmoid, kLinear };

const char* to_string(Kind k);
const char* to_string(Activation a);
kernel::Result<Kind> parse_kind(std::string_view text);
kernel::Result<Activation> parse_activation(std::string_view text);

// Sizes a network may have: enough for a robot's sensors and the evolved controllers in the
// literature, small enough that a bad description cannot eat the memory of a microcontroller.
inline constexpr std::size_t kMaxInputs = 32;
inline constexpr std::size_t kMaxLayerSize = 64;
inline constexpr std::size_t kMaxLayers = 8;
inline constexpr std::size_t kMaxGenome = 20000;

struct Topology {
  Kind kind = Kind::kMlp;
  std::size_t inputs = 7;
  // mlp/elman: the sizes of the hidden layers then the output layer ("2" is a perceptron with two
  // outputs; "4 2" one hidden layer of 4). ctrnn: {N, outputs}: N neurons, the last `outputs` of
  // them read out.
  std::vector<std::size_t> layers{2};
  Activation activation = Activation::kTanh;  // mlp/elman; a ctrnn always uses the logistic sigma
};

// Checks a topology; the error says what is wrong.
kernel::Status check(const Topology& t);
std::size_t genome_size(const Topology& t);
// The number of values step() returns.
std::size_t output_count(const Topology& t);

class Network {
 public:
  // Checks the topology; weights start at zero, state at rest.
  static kernel::Result<Network> create(Topology topology);
  // Builds a network straight from a genome (create() then set_genome()): how evolution makes one.
  static kernel::Result<Network> from_genome(Topology topology, std::span<const float> genome);

  const Topology& topology() const { return topology_; }
  std::size_t genome_size() const { return genome_.size(); }
  std::size_t input_count() const { return topology_.inputs; }
  std::size_t output_count() const { return outputs_.size(); }
  std::span<const float> genome() const { return genome_; }
  // Copies `genome` (exactly genome_size() finite values) into the weights; the state is kept (a
  // ctrnn's firing rates are recomputed from it with the new biases).
  kernel::Status set_genome(std::span<const float> genome);
  // ctrnn: the time constants, one for all neurons or one per neuron, each > 0 (seconds); and the
  // Euler step (seconds, > 0). Ignored by the other kinds.
  kernel::Status set_time_constants(std::span<const float> tau);
  kernel::Status set_step(double dt_seconds);
  std::span<const float> time_constants() const { return tau_; }
  double step_seconds() const { return dt_; }

  // Zeroes the state (Elman context, CTRNN y).
  void reset();
  // One step on `inputs` (input_count() values; missing ones count as 0, extra ones are ignored).
  // Non-finite inputs count as 0. Returns the outputs, always finite.
  std::span<const float> step(std::span<const float> inputs);
  std::span<const float> outputs() const { return outputs_; }

  // Internal state for probes: layer 0 is the input as seen, then every hidden layer, then the
  // output layer (mlp/elman); for a ctrnn layer 0 is the input, layer 1 the neuron states y.
  std::size_t layer_count() const { return activations_.size(); }
  std::span<const float> layer(std::size_t i) const { return activations_.at(i); }
  // A name for layer i: "input", "hidden1".., "output", or "state" (ctrnn).
  std::string layer_name(std::size_t i) const;

 private:
  explicit Network(Topology t);
  void step_layers(std::span<const float> inputs);
  void step_ctrnn(std::span<const float> inputs);
  void refresh_rates();  // ctrnn: sigma(y + theta) and the outputs from the current state

  Topology topology_;
  std::vector<float> genome_;
  std::vector<std::vector<float>> activations_;
  std::vector<float> context_;  // elman: the first hidden layer's previous activations
  std::vector<float> tau_;      // ctrnn: per neuron
  std::vector<float> rates_;    // ctrnn: sigma(y + theta) of the previous state
  double dt_ = 0.03;
  std::vector<float> outputs_;
};

}  // namespace symb::control::network
