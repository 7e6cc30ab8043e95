#include "symb/control/snn/network_layout.hpp"

#include <cmath>
#include <string>

namespace symb::control::snn {

using kernel::Error;

std::vector<float> layout_values(const GrownNetwork& net) {
  const std::size_t n = net.spec.neurons.size();
  std::vector<float> out;
  out.reserve(7 + 5 * n + 4 * net.spec.synapses.size());
  auto f = [](auto v) { return static_cast<float>(v); };
  out.insert(out.end(), {kLayoutVersion, f(net.width), f(net.height), f(n), f(net.spec.synapses.size()),
                         f(net.inputs.size()), f(net.outputs.size())});
  for (std::size_t i = 0; i < n; ++i) {
    const float bias = net.spec.bias.empty() ? 0.0f : net.spec.bias[i];
    out.insert(out.end(), {f(net.x[i]), f(net.y[i]), f(static_cast<int>(net.classes[i])), bias, f(net.cell_ids[i])});
  }
  for (const Synapse& s : net.spec.synapses) out.insert(out.end(), {f(s.source), f(s.target), s.weight, f(s.delay)});
  for (const auto* channels : {&net.inputs, &net.outputs})
    for (const auto& c : *channels) {
      out.push_back(f(c.size()));
      for (std::uint32_t neuron : c) out.push_back(f(neuron));
    }
  return out;
}

kernel::Result<GrownNetwork> layout_from_values(std::span<const float> values) {
  std::size_t at = 0;
  std::string bad;
  // Reads a whole number in [lo, hi]; records the first failure.
  auto whole = [&](const char* what, double lo, double hi) -> std::int64_t {
    if (!bad.empty()) return 0;
    if (at >= values.size()) {
      bad = std::string("cut before ") + what + " (value " + std::to_string(at) + ")";
      return 0;
    }
    const float v = values[at++];
    if (!std::isfinite(v) || v < lo || v > hi || std::floor(v) != v) {
      bad = std::string(what) + " at value " + std::to_string(at - 1) + " is not a whole number in range";
      return 0;
    }
    return static_cast<std::int64_t>(v);
  };
  auto real = [&](const char* what) -> float {
    if (!bad.empty()) return 0;
    if (at >= values.size() || !std::isfinite(values[at])) {
      bad = std::string("bad or missing ") + what + " at value " + std::to_string(at);
      return 0;
    }
    return values[at++];
  };
  GrownNetwork net;
  if (whole("version", kLayoutVersion, kLayoutVersion) != kLayoutVersion && bad.empty()) bad = "unknown version";
  net.width = static_cast<int>(whole("width", 1, kMaxGridSide));
  net.height = static_cast<int>(whole("height", 1, kMaxGridSide));
  const auto n = static_cast<std::size_t>(whole("neuron count", 0, kMaxGridSide * kMaxGridSide));
  const auto s = static_cast<std::size_t>(whole("synapse count", 0, 1e7));
  const auto inputs = static_cast<std::size_t>(whole("input channel count", 0, kMaxChannels));
  const auto outputs = static_cast<std::size_t>(whole("output channel count", 0, kMaxChannels));
  if (!bad.empty()) return Error{"layout: " + bad};
  if (values.size() < at + 5 * n + 4 * s) return Error{"layout: cut (fewer values than its counts say)"};
  for (std::size_t i = 0; i < n && bad.empty(); ++i) {
    net.x.push_back(static_cast<int>(whole("x", 0, net.width - 1)));
    net.y.push_back(static_cast<int>(whole("y", 0, net.height - 1)));
    const auto cls = static_cast<NeuronClass>(whole("class", 0, kNeuronClassCount - 1));
    net.classes.push_back(cls);
    net.spec.neurons.push_back(params_of(cls));
    net.spec.bias.push_back(real("bias"));
    net.cell_ids.push_back(static_cast<std::uint32_t>(whole("cell id", 0, 1e7)));
  }
  for (std::size_t i = 0; i < s && bad.empty(); ++i) {
    Synapse syn;
    syn.source = static_cast<std::uint32_t>(whole("synapse source", 0, static_cast<double>(n) - 1));
    syn.target = static_cast<std::uint32_t>(whole("synapse target", 0, static_cast<double>(n) - 1));
    syn.weight = real("synapse weight");
    syn.delay = static_cast<std::uint32_t>(whole("synapse delay", 0, kMaxDelay));
    net.spec.synapses.push_back(syn);
  }
  for (auto [channels, count] : {std::pair{&net.inputs, inputs}, std::pair{&net.outputs, outputs}}) {
    for (std::size_t c = 0; c < count && bad.empty(); ++c) {
      const auto k = static_cast<std::size_t>(whole("channel size", 0, static_cast<double>(n)));
      std::vector<std::uint32_t> neurons;
      for (std::size_t j = 0; j < k && bad.empty(); ++j)
        neurons.push_back(static_cast<std::uint32_t>(whole("channel neuron", 0, static_cast<double>(n) - 1)));
      channels->push_back(std::move(neurons));
    }
  }
  if (!bad.empty()) return Error{"layout: " + bad};
  if (at != values.size()) return Error{"layout: " + std::to_string(values.size() - at) + " values too many"};
  return net;
}

}  // namespace symb::control::snn
