#include "symb/control/network/network_task_types.hpp"

#include <cmath>
#include <memory>
#include <string>

#include "symb/control/network/description.hpp"
#include "symb/control/network/network_task.hpp"

namespace symb::control {

namespace {

using namespace std::chrono_literals;
using network::Kind;

constexpr double kMaxText = 200000;  // characters of an inline weight list

std::string shown(const std::string& reference) {
  return reference.size() <= 120 ? reference : reference.substr(0, 120) + "...";
}

using kernel::Error;
using kernel::Result;

// The network types' parameters: the task's options and model parameters, and what the factories
// read to build the network.
struct NetworkParams : NetworkTaskOptions, NetworkModelParams {
  std::int64_t inputs = 7;
  std::string layers = "2";
  std::string activation = "tanh";
  std::string description;
};

Result<std::vector<std::size_t>> parse_layers(const std::string& text) {
  auto numbers = network::parse_numbers(text, network::kMaxLayers);
  if (!numbers) return Error{"layers: " + numbers.error()};
  std::vector<std::size_t> layers;
  for (float v : *numbers) {
    if (v < 1 || v > static_cast<float>(network::kMaxLayerSize) || std::floor(v) != v)
      return Error{"layers: sizes are whole numbers 1.." + std::to_string(network::kMaxLayerSize)};
    layers.push_back(static_cast<std::size_t>(v));
  }
  return layers;
}

Result<std::vector<float>> parse_list(const char* name, const std::string& text, std::size_t max) {
  auto numbers = network::parse_numbers(text, max);
  if (!numbers) return Error{std::string(name) + ": " + numbers.error()};
  if (numbers->empty()) return Error{std::string(name) + ": give at least one number"};
  return numbers;
}

// The network with its weights and time constants set, and the task around it.
Result<std::unique_ptr<NetworkTask>> build(network::Topology topology, const std::vector<float>& weights,
                                           const std::vector<float>& tau, double dt, NetworkTaskOptions options,
                                           const std::shared_ptr<const ControlResources>& resources) {
  auto net = network::Network::create(std::move(topology));
  if (!net) return Error{net.error()};
  if (!weights.empty())
    if (auto st = net.value().set_genome(weights); !st) return Error{"weights: " + st.error()};
  if (net->topology().kind == Kind::kCtrnn) {
    if (!tau.empty())
      if (auto st = net.value().set_time_constants(tau); !st) return Error{"tau: " + st.error()};
    if (auto st = net.value().set_step(dt); !st) return Error{"dt: " + st.error()};
  }
  return NetworkTask::create(std::move(net).value(), std::move(options), resources);
}

double seconds(kernel::Duration d) { return std::chrono::duration<double>(d).count(); }

os::ParamCodec<NetworkOutput> output_codec() {
  os::ParamCodec<NetworkOutput> c;
  c.type = os::ParamType::kString;
  c.parse = [](const os::ParamValue& v) { return parse_network_output(std::get<std::string>(v)); };
  c.format = [](NetworkOutput o) -> os::ParamValue {
    return std::string(o == NetworkOutput::kRaw ? "raw" : o == NetworkOutput::kBoth ? "both" : "wheels");
  };
  return c;
}

os::ParamCodec<std::vector<float>> input_scale_codec() {
  os::ParamCodec<std::vector<float>> c;
  c.type = os::ParamType::kString;
  c.parse = [](const os::ParamValue& v) {
    return parse_list("input_scale", std::get<std::string>(v), network::kMaxInputs);
  };
  // The default is given as text (1/4505 to the digits the docs show).
  c.format = [](const std::vector<float>&) -> os::ParamValue { return std::string(); };
  return c;
}

void add_common(os::ParamTable<NetworkParams>& p, const char* weights_doc, const char* output_scale_doc) {
  using P = NetworkParams;
  p.add("weights", &P::weights).range(0.0, kMaxText).doc(weights_doc).live();
  p.add("output_scale", &P::output_scale).range(1e-6, 1e6).doc(output_scale_doc).live();
  p.add("speed_limit", &P::speed_limit).range(1e-6, 1e6).doc("wheel commands are clamped to +-this").live();
  p.add("output", &P::output, output_codec())
      .range(1.0, 16.0)
      .doc("wheels: [left, right] on port 0; raw: the output vector on port 0; both: wheels on 0, raw on 1");
  p.add("input_port", &P::input_port)
      .range(0.0, 65535.0)
      .doc("the port input vectors arrive on (1 to read a network's raw outputs sent with output=both)");
  p.add("warn_interval", &P::warn_interval).range(0.0, 3600.0).doc("at most one warning per interval").live();
}

void add_dt(os::ParamTable<NetworkParams>& p, const char* doc) {
  p.add("dt", &NetworkParams::dt).range(1e-6, 10.0).doc(doc).live();
}

os::TaskType network_type(Kind kind, const std::shared_ptr<const ControlResources>& resources) {
  std::string doc;
  const char* io = "; input vector in on input_port, [left, right] wheel units or the raw outputs out (see output)";
  switch (kind) {
    case Kind::kMlp: doc = std::string("feed-forward network (perceptron / MLP)") + io; break;
    case Kind::kElman:
      doc = std::string("Elman recurrent network (context units on the first hidden layer)") + io;
      break;
    case Kind::kCtrnn:
      doc = std::string("continuous-time recurrent network (Beer 1995), one Euler step of dt per input") + io;
      break;
  }
  using P = NetworkParams;
  P defaults;
  defaults.layers = kind == Kind::kMlp ? "2" : "4 2";
  os::ParamTable<P> p(defaults);
  p.add("inputs", &P::inputs).range(1.0, static_cast<double>(network::kMaxInputs)).doc("input vector length");
  p.add("layers", &P::layers)
      .range(1.0, 200.0)
      .doc(kind == Kind::kCtrnn ? "\"N O\": N neurons, the last O read out"
                                : "hidden layer sizes then the output size");
  p.add("input_scale", &P::input_scale, input_scale_codec())
      .range(1.0, 2000.0)
      .default_value(std::string("0.000221975583"))
      .doc("inputs are multiplied by this (one factor or one per input); default 1/4505 for IR")
      .live();
  if (kind == Kind::kCtrnn) {
    p.add("tau", &P::tau).range(1.0, 2000.0).doc("time constants in seconds (one, or one per neuron)").live();
    add_dt(p, "the Euler step: virtual time per network step (the sensor period)");
  } else {
    p.add("activation", &P::activation).range(1.0, 16.0).doc("tanh, sigmoid or linear");
  }
  add_common(p, "the genome: numbers (\"0.5 -0.2 ...\") or a weight file reference; empty: all zero",
             "an output of 1 drives a wheel at this speed");
  auto t = os::declare_task_type(network::to_string(kind), std::move(doc), std::move(p),
                                 [kind, resources](const P& o) -> Result<std::unique_ptr<NetworkTask>> {
                                   network::Topology topology;
                                   topology.kind = kind;
                                   topology.inputs = static_cast<std::size_t>(o.inputs);
                                   auto layers = parse_layers(o.layers);
                                   if (!layers) return Error{layers.error()};
                                   topology.layers = std::move(layers).value();
                                   std::vector<float> tau;
                                   double dt = 0.03;
                                   if (kind == Kind::kCtrnn) {
                                     auto taus = parse_list("tau", o.tau, network::kMaxLayerSize);
                                     if (!taus) return Error{taus.error()};
                                     tau = std::move(taus).value();
                                     dt = seconds(o.dt);
                                   } else {
                                     auto a = network::parse_activation(o.activation);
                                     if (!a) return Error{"activation: " + a.error()};
                                     topology.activation = *a;
                                   }
                                   if (auto st = network::check(topology); !st) return Error{st.error()};
                                   auto weights = read_weights(o.weights, *resources);
                                   if (!weights) return Error{"weights: " + weights.error()};
                                   return build(std::move(topology), *weights, tau, dt, o, resources);
                                 });
  t.defaults.priority = 2;
  t.defaults.queue_capacity = 4;
  return t;
}

os::TaskType described_type(const std::shared_ptr<const ControlResources>& resources) {
  using P = NetworkParams;
  os::ParamTable<P> p;
  p.add("description", &P::description).range(0.0, 1024.0).doc("the description (a reference the node resolves)");
  add_dt(p, "ctrnn: the Euler step per network step");
  add_common(p, "replaces the description's weights (numbers or a weight file); empty: keep them",
             "used when the description gives none");
  auto t = os::declare_task_type(
      "network",
      "a network described in a text file (type, layers, weights, scales; docs/networks.md): same ports as mlp",
      std::move(p), [resources](const P& o) -> Result<std::unique_ptr<NetworkTask>> {
        const std::string& reference = o.description;
        if (reference.empty()) return Error{"name the description: description=REFERENCE"};
        if (!resources->read_program) return Error{"this node cannot read descriptions (no read_program)"};
        auto text = resources->read_program(reference);
        if (!text) return Error{"description '" + shown(reference) + "': " + text.error()};
        auto d = network::parse_description(*text);
        if (!d) return Error{"description '" + shown(reference) + "': " + d.error()};
        std::vector<float> weights = d->weights.value_or(std::vector<float>{});
        if (!o.weights.empty()) {
          auto w = read_weights(o.weights, *resources);
          if (!w) return Error{"weights: " + w.error()};
          weights = std::move(w).value();
        }
        NetworkTaskOptions options = o;
        if (!d->input_scale.empty()) options.input_scale = d->input_scale;
        if (d->output_scale) options.output_scale = *d->output_scale;
        return build(d->topology, weights, d->tau, seconds(o.dt), std::move(options), resources);
      });
  t.defaults.priority = 2;
  t.defaults.queue_capacity = 4;
  return t;
}

}  // namespace

kernel::Status register_network_task_types(os::TaskTypeRegistry& registry, const ControlResources& resources) {
  auto shared = std::make_shared<const ControlResources>(resources);
  for (Kind k : {Kind::kMlp, Kind::kElman, Kind::kCtrnn})
    if (auto st = registry.add(network_type(k, shared)); !st) return st;
  return registry.add(described_type(shared));
}

}  // namespace symb::control
