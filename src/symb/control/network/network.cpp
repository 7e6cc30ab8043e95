#include "symb/control/network/network.hpp"

#include <algorithm>
#include <cmath>

namespace symb::control::network {

using kernel::Error;

namespace {

float sigma(double x) { return static_cast<float>(1.0 / (1.0 + std::exp(-x))); }

float activate(Activation a, double x) {
  switch (a) {
    case Activation::kTanh: return static_cast<float>(std::tanh(x));
    case Activation::kSigmoid: return sigma(x);
    case Activation::kLinear: break;
  }
  // A linear unit may grow without bound; keep it finite and within float range.
  if (!std::isfinite(x)) return 0.0f;
  return static_cast<float>(std::clamp(x, -1e6, 1e6));
}

float finite_or_zero(float v) { return std::isfinite(v) ? v : 0.0f; }

}  // namespace

const char* to_string(Kind k) {
  switch (k) {
    case Kind::kMlp: return "mlp";
    case Kind::kElman: return "elman";
    case Kind::kCtrnn: return "ctrnn";
  }
  return "?";
}

const char* to_string(Activation a) {
  switch (a) {
    case Activation::kTanh: return "tanh";
    case Activation::kSigmoid: return "sigmoid";
    case Activation::kLinear: return "linear";
  }
  return "?";
}

kernel::Result<Kind> parse_kind(std::string_view text) {
  if (text == "mlp") return Kind::kMlp;
  if (text == "elman") return Kind::kElman;
  if (text == "ctrnn") return Kind::kCtrnn;
  return Error{"unknown network type '" + std::string(text.substr(0, 40)) + "' (mlp, elman or ctrnn)"};
}

kernel::Result<Activation> parse_activation(std::string_view text) {
  if (text == "tanh") return Activation::kTanh;
  if (text == "sigmoid") return Activation::kSigmoid;
  if (text == "linear") return Activation::kLinear;
  return Error{"unknown activation '" + std::string(text.substr(0, 40)) + "' (tanh, sigmoid or linear)"};
}

kernel::Status check(const Topology& t) {
  if (t.inputs < 1 || t.inputs > kMaxInputs)
    return Error{"inputs must be 1.." + std::to_string(kMaxInputs) + ", got " + std::to_string(t.inputs)};
  if (t.layers.empty()) return Error{"no layers: give at least the output layer's size"};
  if (t.layers.size() > kMaxLayers) return Error{"at most " + std::to_string(kMaxLayers) + " layers"};
  for (std::size_t n : t.layers)
    if (n < 1 || n > kMaxLayerSize)
      return Error{"a layer must have 1.." + std::to_string(kMaxLayerSize) + " neurons, got " + std::to_string(n)};
  if (t.kind == Kind::kElman && t.layers.size() < 2)
    return Error{"an elman network needs a hidden layer (the one with context units): layers \"H O\""};
  if (t.kind == Kind::kCtrnn) {
    if (t.layers.size() != 2) return Error{"a ctrnn takes layers \"N O\": N neurons, the last O of them outputs"};
    if (t.layers[1] > t.layers[0]) return Error{"a ctrnn cannot read out more neurons than it has"};
  }
  if (genome_size(t) > kMaxGenome) return Error{"more than " + std::to_string(kMaxGenome) + " weights"};
  return {};
}

std::size_t genome_size(const Topology& t) {
  if (t.layers.empty()) return 0;
  if (t.kind == Kind::kCtrnn) return t.layers[0] * (t.inputs + t.layers[0] + 1);
  std::size_t size = 0, below = t.inputs;
  for (std::size_t l = 0; l < t.layers.size(); ++l) {
    const std::size_t context = (t.kind == Kind::kElman && l == 0) ? t.layers[0] : 0;
    size += (below + context + 1) * t.layers[l];
    below = t.layers[l];
  }
  return size;
}

std::size_t output_count(const Topology& t) { return t.layers.empty() ? 0 : t.layers.back(); }

kernel::Result<Network> Network::create(Topology topology) {
  if (auto st = check(topology); !st) return Error{st.error()};
  return Network(std::move(topology));
}

kernel::Result<Network> Network::from_genome(Topology topology, std::span<const float> genome) {
  auto n = create(std::move(topology));
  if (!n) return n;
  if (auto st = n.value().set_genome(genome); !st) return Error{st.error()};
  return n;
}

Network::Network(Topology t) : topology_(std::move(t)) {
  genome_.assign(control::network::genome_size(topology_), 0.0f);
  activations_.emplace_back(topology_.inputs, 0.0f);
  if (topology_.kind == Kind::kCtrnn) {
    const std::size_t n = topology_.layers[0];
    activations_.emplace_back(n, 0.0f);
    tau_.assign(n, 1.0f);
    rates_.assign(n, 0.5f);
    outputs_.assign(topology_.layers[1], 0.5f);
  } else {
    for (std::size_t n : topology_.layers) activations_.emplace_back(n, 0.0f);
    if (topology_.kind == Kind::kElman) context_.assign(topology_.layers[0], 0.0f);
    outputs_.assign(topology_.layers.back(), 0.0f);
  }
  reset();
}

kernel::Status Network::set_genome(std::span<const float> genome) {
  if (genome.size() != genome_.size())
    return Error{"the genome of this network has " + std::to_string(genome_.size()) + " values, got " +
                 std::to_string(genome.size())};
  for (std::size_t k = 0; k < genome.size(); ++k)
    if (!std::isfinite(genome[k])) return Error{"genome value " + std::to_string(k) + " is not a finite number"};
  std::copy(genome.begin(), genome.end(), genome_.begin());
  if (topology_.kind == Kind::kCtrnn) refresh_rates();  // the rates depend on the biases
  return {};
}

kernel::Status Network::set_time_constants(std::span<const float> tau) {
  if (tau.size() != 1 && tau.size() != tau_.size())
    return Error{"give one time constant or one per neuron (" + std::to_string(tau_.size()) + "), got " +
                 std::to_string(tau.size())};
  for (float v : tau)
    if (!std::isfinite(v) || v <= 0) return Error{"time constants must be positive numbers"};
  for (std::size_t i = 0; i < tau_.size(); ++i) tau_[i] = tau.size() == 1 ? tau[0] : tau[i];
  return {};
}

kernel::Status Network::set_step(double dt_seconds) {
  if (!std::isfinite(dt_seconds) || dt_seconds <= 0) return Error{"the step dt must be a positive duration"};
  dt_ = dt_seconds;
  return {};
}

void Network::reset() {
  for (auto& a : activations_) std::fill(a.begin(), a.end(), 0.0f);
  std::fill(context_.begin(), context_.end(), 0.0f);
  if (topology_.kind == Kind::kCtrnn) {
    refresh_rates();
  } else {
    std::fill(outputs_.begin(), outputs_.end(), 0.0f);
  }
}

std::span<const float> Network::step(std::span<const float> inputs) {
  std::vector<float>& in = activations_[0];
  for (std::size_t k = 0; k < in.size(); ++k) in[k] = k < inputs.size() ? finite_or_zero(inputs[k]) : 0.0f;
  if (topology_.kind == Kind::kCtrnn)
    step_ctrnn(in);
  else
    step_layers(in);
  for (float& o : outputs_) o = finite_or_zero(o);
  return outputs_;
}

void Network::step_layers(std::span<const float> inputs) {
  const float* w = genome_.data();
  std::span<const float> below = inputs;
  for (std::size_t l = 0; l < topology_.layers.size(); ++l) {
    std::vector<float>& out = activations_[l + 1];
    const bool with_context = topology_.kind == Kind::kElman && l == 0;
    for (std::size_t j = 0; j < out.size(); ++j) {
      double sum = 0;
      for (float x : below) sum += static_cast<double>(*w++) * x;
      if (with_context)
        for (float c : context_) sum += static_cast<double>(*w++) * c;
      sum += *w++;
      out[j] = activate(topology_.activation, sum);
    }
    below = out;
  }
  if (topology_.kind == Kind::kElman) context_ = activations_[1];
  const std::vector<float>& last = activations_.back();
  std::copy(last.begin(), last.end(), outputs_.begin());
}

void Network::step_ctrnn(std::span<const float> inputs) {
  const std::size_t n = topology_.layers[0], stride = topology_.inputs + n + 1;
  std::vector<float>& y = activations_[1];
  // Every neuron sees the rates of the same (previous) state: a synchronous Euler step.
  for (std::size_t i = 0; i < n; ++i) {
    const float* g = genome_.data() + i * stride;
    double drive = 0;
    for (std::size_t k = 0; k < inputs.size(); ++k) drive += static_cast<double>(g[k]) * inputs[k];
    for (std::size_t j = 0; j < n; ++j) drive += static_cast<double>(g[inputs.size() + j]) * rates_[j];
    const double next = y[i] + dt_ / tau_[i] * (-static_cast<double>(y[i]) + drive);
    // A step longer than tau overshoots; keep the state finite whatever the parameters.
    y[i] = std::isfinite(next) ? static_cast<float>(std::clamp(next, -1e6, 1e6)) : 0.0f;
  }
  refresh_rates();
}

void Network::refresh_rates() {
  const std::size_t n = topology_.layers[0], stride = topology_.inputs + n + 1;
  const std::vector<float>& y = activations_[1];
  for (std::size_t i = 0; i < n; ++i) rates_[i] = sigma(static_cast<double>(y[i]) + genome_[i * stride + stride - 1]);
  for (std::size_t o = 0; o < outputs_.size(); ++o) outputs_[o] = rates_[n - outputs_.size() + o];
}

std::string Network::layer_name(std::size_t i) const {
  if (i == 0) return "input";
  if (topology_.kind == Kind::kCtrnn) return "state";
  if (i + 1 == activations_.size()) return "output";
  return "hidden" + std::to_string(i);
}

}  // namespace symb::control::network
