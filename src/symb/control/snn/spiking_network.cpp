#include "symb/control/snn/spiking_network.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>

namespace symb::control::snn {

namespace {

constexpr std::size_t kRingSlots = kMaxDelay + 1;
static_assert((kRingSlots & (kRingSlots - 1)) == 0, "the ring index is a mask");

std::string neuron_count(std::size_t n) { return "(network has " + std::to_string(n) + " neurons)"; }

kernel::Status check_spec(const NetworkSpec& spec) {
  const std::size_t n = spec.neurons.size();
  if (n == 0) return kernel::Error{"network has no neurons"};
  if (n > kMaxNeurons)
    return kernel::Error{"network has " + std::to_string(n) + " neurons (at most " + std::to_string(kMaxNeurons) + ")"};
  for (std::size_t i = 0; i < n; ++i) {
    const NeuronParams& p = spec.neurons[i];
    const float values[] = {p.a, p.b, p.c, p.d};
    const char* names[] = {"a", "b", "c", "d"};
    for (int k = 0; k < 4; ++k)
      if (!std::isfinite(values[k]))
        return kernel::Error{"neuron " + std::to_string(i) + ": parameter " + names[k] + " is not finite"};
  }
  if (!spec.bias.empty() && spec.bias.size() != n)
    return kernel::Error{"bias has " + std::to_string(spec.bias.size()) + " values, expected 0 or " +
                         std::to_string(n) + " " + neuron_count(n)};
  for (std::size_t i = 0; i < spec.bias.size(); ++i)
    if (!std::isfinite(spec.bias[i]) || std::abs(spec.bias[i]) > kMaxAbsBias)
      return kernel::Error{"bias " + std::to_string(i) + ": " + std::to_string(spec.bias[i]) +
                           " is not a finite number within +-" + std::to_string(static_cast<int>(kMaxAbsBias))};
  if (spec.synapses.size() >= std::numeric_limits<std::uint32_t>::max())
    return kernel::Error{"too many synapses (" + std::to_string(spec.synapses.size()) + ")"};
  for (std::size_t k = 0; k < spec.synapses.size(); ++k) {
    const Synapse& s = spec.synapses[k];
    auto where = [k] { return "synapse " + std::to_string(k) + ": "; };  // built only on an error
    if (s.source >= n)
      return kernel::Error{where() + "source " + std::to_string(s.source) + " out of range " + neuron_count(n)};
    if (s.target >= n)
      return kernel::Error{where() + "target " + std::to_string(s.target) + " out of range " + neuron_count(n)};
    if (!std::isfinite(s.weight) || std::abs(s.weight) > kMaxAbsWeight)
      return kernel::Error{where() + "weight " + std::to_string(s.weight) + " is not a finite number within +-" +
                           std::to_string(static_cast<int>(kMaxAbsWeight))};
    if (s.delay > kMaxDelay)
      return kernel::Error{where() + "delay " + std::to_string(s.delay) + " ms out of range (0.." +
                           std::to_string(kMaxDelay) + ")"};
  }
  return kernel::Status::success();
}

// The update loop works on four neurons at a time in GCC/Clang vector types: GCC's -O2 (the
// project's RelWithDebInfo) vectorises no loop of unknown length, and a float select on a
// comparison is control flow to it under -ftrapping-math. Vector lanes compute in IEEE single
// precision exactly as scalar code does, so lanes and the scalar tail agree with step_neuron().
using Float4 = float __attribute__((vector_size(16)));
using Mask4 = std::int32_t __attribute__((vector_size(16)));

// mask ? x : y, masks all ones or all zeros (what a vector comparison yields).
inline Float4 select(Mask4 mask, Float4 x, Float4 y) {
  return reinterpret_cast<Float4>((reinterpret_cast<Mask4>(x) & mask) | (reinterpret_cast<Mask4>(y) & ~mask));
}
inline float select(bool mask, float x, float y) { return mask ? x : y; }

template <class T>
inline T load(const float* p) {
  T x;
  std::memcpy(&x, p, sizeof x);
  return x;
}
template <class T>
inline void store(float* p, T x) {
  std::memcpy(p, &x, sizeof x);
}

struct Arrays {
  const float* a;
  const float* b;
  const float* c;
  const float* d;
  float* v;
  float* u;
  const float* bias;
  float* input;
  float* pulses;
};

// One step of the neurons at i (one float or a Float4 of them), fire mask included: step_neuron()'s
// arithmetic expression for expression (izhikevich.cpp), since the two must agree bit for bit.
template <Integration kScheme, class T>
inline void update(const Arrays& x, std::size_t i) {
  const T v0 = load<T>(x.v + i), u0 = load<T>(x.u + i);
  const auto fired = v0 >= kPeakVoltage;
  const T v = select(fired, load<T>(x.c + i), v0);
  const T u = select(fired, u0 + load<T>(x.d + i), u0);
  const T current = load<T>(x.bias + i) + load<T>(x.input + i) + load<T>(x.pulses + i);
  if constexpr (kScheme == Integration::kPublished) {
    const T v1 = v + 0.5f * (0.04f * (v * v) + 5.0f * v + 140.0f - u + current);
    const T v2 = v1 + 0.5f * (0.04f * (v1 * v1) + 5.0f * v1 + 140.0f - u + current);
    store(x.v + i, v2);
    store(x.u + i, u + load<T>(x.a + i) * (load<T>(x.b + i) * v2 - u));
  } else {
    store(x.v + i, v + (0.04f * (v * v) + 5.0f * v + 140.0f - u + current));
    store(x.u + i, u + load<T>(x.a + i) * (load<T>(x.b + i) * v - u));
  }
  store(x.input + i, T{});
  store(x.pulses + i, T{});
}

template <Integration kScheme>
void update_all(const Arrays& x, std::size_t n) {
  constexpr std::size_t kLanes = sizeof(Float4) / sizeof(float);
  std::size_t i = 0;
  for (; i + kLanes <= n; i += kLanes) update<kScheme, Float4>(x, i);
  for (; i < n; ++i) update<kScheme, float>(x, i);
}

}  // namespace

kernel::Result<SpikingNetwork> SpikingNetwork::create(const NetworkSpec& spec) {
  if (auto ok = check_spec(spec); !ok) return kernel::Error{ok.error()};
  const std::size_t n = spec.neurons.size();
  SpikingNetwork net;
  net.integration_ = spec.integration;
  net.a_.resize(n);
  net.b_.resize(n);
  net.c_.resize(n);
  net.d_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    net.a_[i] = spec.neurons[i].a;
    net.b_[i] = spec.neurons[i].b;
    net.c_[i] = spec.neurons[i].c;
    net.d_[i] = spec.neurons[i].d;
  }
  net.bias_ = spec.bias.empty() ? std::vector<float>(n, 0.0f) : spec.bias;

  // Compressed rows by source: a stable counting sort keeps spec order within a row.
  net.row_start_.assign(n + 1, 0);
  for (const Synapse& s : spec.synapses) ++net.row_start_[s.source + 1];
  for (std::size_t i = 0; i < n; ++i) net.row_start_[i + 1] += net.row_start_[i];
  const std::size_t m = spec.synapses.size();
  net.targets_.resize(m);
  net.weights_.resize(m);
  net.delays_.resize(m);
  std::vector<std::uint32_t> next(net.row_start_.begin(), net.row_start_.end() - 1);
  for (const Synapse& s : spec.synapses) {
    const std::uint32_t k = next[s.source]++;
    net.targets_[k] = s.target;
    net.weights_[k] = s.weight;
    net.delays_[k] = static_cast<std::uint8_t>(s.delay);
  }
  net.v_.resize(n);
  net.u_.resize(n);
  net.input_.resize(n);
  net.ring_.resize(kRingSlots * n);
  net.fired_.reserve(n);
  net.reset();
  return net;
}

std::span<const std::uint32_t> SpikingNetwork::step() {
  const std::size_t n = size();
  // (1) Who fires: a separate pass, so the update loop below stays branch-free.
  fired_.clear();
  for (std::size_t i = 0; i < n; ++i)
    if (v_[i] >= kPeakVoltage) fired_.push_back(static_cast<std::uint32_t>(i));
  // (2) Their pulses into the ring slot of step t + delay (delay 0: this step's slot).
  float* const ring = ring_.data();
  const std::uint64_t t = time_ms_;
  if (!fired_.empty()) {
    float* slot_of_delay[kRingSlots];
    for (std::size_t k = 0; k < kRingSlots; ++k) slot_of_delay[k] = ring + ((t + k) & (kRingSlots - 1)) * n;
    for (const std::uint32_t j : fired_) {
      const std::uint32_t end = row_start_[j + 1];
      for (std::uint32_t k = row_start_[j]; k < end; ++k) slot_of_delay[delays_[k]][targets_[k]] += weights_[k];
    }
  }
  // (3)-(5) Reset the fired, sum the currents, integrate, clear the input and this step's slot.
  float* const pulses = ring + static_cast<std::size_t>(t & (kRingSlots - 1)) * n;
  const Arrays x{a_.data(), b_.data(), c_.data(), d_.data(), v_.data(), u_.data(), bias_.data(), input_.data(), pulses};
  if (integration_ == Integration::kPublished)
    update_all<Integration::kPublished>(x, n);
  else
    update_all<Integration::kEuler>(x, n);
  ++time_ms_;
  return fired_;
}

NeuronParams SpikingNetwork::params(std::uint32_t neuron) const {
  if (neuron >= size()) return {};
  return {a_[neuron], b_[neuron], c_[neuron], d_[neuron]};
}

std::vector<Synapse> SpikingNetwork::synapses_of(std::uint32_t source) const {
  std::vector<Synapse> out;
  if (source >= size()) return out;
  for (std::uint32_t k = row_start_[source]; k < row_start_[source + 1]; ++k)
    out.push_back({source, targets_[k], weights_[k], delays_[k]});
  return out;
}

NetworkSpec SpikingNetwork::spec() const {
  NetworkSpec s;
  s.integration = integration_;
  s.bias = bias_;
  s.neurons.reserve(size());
  for (std::uint32_t i = 0; i < size(); ++i) s.neurons.push_back(params(i));
  s.synapses.reserve(synapse_count());
  for (std::uint32_t i = 0; i < size(); ++i)
    for (std::uint32_t k = row_start_[i]; k < row_start_[i + 1]; ++k)
      s.synapses.push_back({i, targets_[k], weights_[k], delays_[k]});
  return s;
}

void SpikingNetwork::reset() {
  for (std::size_t i = 0; i < size(); ++i) {
    v_[i] = kRestVoltage;
    u_[i] = b_[i] * kRestVoltage;
  }
  std::fill(input_.begin(), input_.end(), 0.0f);
  std::fill(ring_.begin(), ring_.end(), 0.0f);
  fired_.clear();
  time_ms_ = 0;
}

}  // namespace symb::control::snn
