#include "symb/control/network_task_types.hpp"

#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

#include "symb/control/network/description.hpp"
#include "symb/control/network_task.hpp"

namespace symb::control {

namespace {

using namespace std::chrono_literals;
using network::Kind;
using os::ParamSpec;
using os::ParamType;

constexpr double kMaxText = 200000;  // characters of an inline weight list

std::string shown(const std::string& reference) {
  return reference.size() <= 120 ? reference : reference.substr(0, 120) + "...";
}

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument(what); }

std::vector<std::size_t> parse_layers(const std::string& text) {
  auto numbers = network::parse_numbers(text, network::kMaxLayers);
  if (!numbers) fail("layers: " + numbers.error());
  std::vector<std::size_t> layers;
  for (float v : *numbers) {
    if (v < 1 || v > static_cast<float>(network::kMaxLayerSize) || std::floor(v) != v)
      fail("layers: sizes are whole numbers 1.." + std::to_string(network::kMaxLayerSize));
    layers.push_back(static_cast<std::size_t>(v));
  }
  return layers;
}

std::vector<float> parse_list(const char* name, const std::string& text, std::size_t max) {
  auto numbers = network::parse_numbers(text, max);
  if (!numbers) fail(std::string(name) + ": " + numbers.error());
  if (numbers->empty()) fail(std::string(name) + ": give at least one number");
  return std::move(numbers).value();
}

// The network with its weights and time constants set, and the task around it.
std::unique_ptr<os::Task> build(network::Topology topology, const std::vector<float>& weights,
                                const std::vector<float>& tau, double dt, NetworkTaskOptions options,
                                const std::shared_ptr<const ControlResources>& resources) {
  auto net = network::Network::create(std::move(topology));
  if (!net) fail(net.error());
  if (!weights.empty())
    if (auto st = net.value().set_genome(weights); !st) fail("weights: " + st.error());
  if (net->topology().kind == Kind::kCtrnn) {
    if (!tau.empty())
      if (auto st = net.value().set_time_constants(tau); !st) fail("tau: " + st.error());
    if (auto st = net.value().set_step(dt); !st) fail("dt: " + st.error());
  }
  auto task = NetworkTask::create(std::move(net).value(), std::move(options), resources);
  if (!task) fail(task.error());
  return std::move(task).value();
}

double seconds(kernel::Duration d) { return std::chrono::duration<double>(d).count(); }

std::vector<ParamSpec> common_params() {
  const NetworkTaskOptions d;
  return {
      {"weights", ParamType::kString, std::string(), 0.0, kMaxText,
       "the genome: numbers (\"0.5 -0.2 ...\") or a weight file reference; empty: all zero"},
      {"output_scale", ParamType::kReal, d.output_scale, 1e-6, 1e6, "an output of 1 drives a wheel at this speed"},
      {"speed_limit", ParamType::kReal, d.speed_limit, 1e-6, 1e6, "wheel commands are clamped to +-this"},
      {"output", ParamType::kString, std::string("wheels"), 1.0, 16.0,
       "wheels: [left, right] on port 0; raw: the output vector on port 0; both: wheels on 0, raw on 1"},
      {"input_port", ParamType::kInt, std::int64_t{0}, 0.0, 65535.0,
       "the port input vectors arrive on (1 to read a network's raw outputs sent with output=both)"},
      {"warn_interval", ParamType::kDuration, d.warn_interval, 0.0, 3600.0, "at most one warning per interval"},
  };
}

NetworkTaskOptions common_options(const os::ParamSet& p) {
  NetworkTaskOptions o;
  o.output_scale = p.real("output_scale");
  o.speed_limit = p.real("speed_limit");
  o.input_port = static_cast<os::Port>(p.integer("input_port"));
  auto output = parse_network_output(p.string("output"));
  if (!output) fail(output.error());
  o.output = *output;
  o.warn_interval = p.duration("warn_interval");
  return o;
}

os::TaskType network_type(Kind kind, const std::shared_ptr<const ControlResources>& resources) {
  os::TaskType t;
  t.name = network::to_string(kind);
  const char* io = "; input vector in on input_port, [left, right] wheel units or the raw outputs out (see output)";
  switch (kind) {
    case Kind::kMlp: t.doc = std::string("feed-forward network (perceptron / MLP)") + io; break;
    case Kind::kElman:
      t.doc = std::string("Elman recurrent network (context units on the first hidden layer)") + io;
      break;
    case Kind::kCtrnn:
      t.doc = std::string("continuous-time recurrent network (Beer 1995), one Euler step of dt per input") + io;
      break;
  }
  t.params = {
      {"inputs", ParamType::kInt, std::int64_t{7}, 1.0, static_cast<double>(network::kMaxInputs),
       "input vector length"},
      {"layers", ParamType::kString, std::string(kind == Kind::kMlp ? "2" : "4 2"), 1.0, 200.0,
       kind == Kind::kCtrnn ? "\"N O\": N neurons, the last O read out" : "hidden layer sizes then the output size"},
      {"input_scale", ParamType::kString, std::string("0.000221975583"), 1.0, 2000.0,
       "inputs are multiplied by this (one factor or one per input); default 1/4505 for IR"},
  };
  if (kind == Kind::kCtrnn) {
    t.params.push_back({"tau", ParamType::kString, std::string("0.1"), 1.0, 2000.0,
                        "time constants in seconds (one, or one per neuron)"});
    t.params.push_back({"dt", ParamType::kDuration, kernel::Duration(30ms), 1e-6, 10.0,
                        "the Euler step: virtual time per network step (the sensor period)"});
  } else {
    t.params.push_back({"activation", ParamType::kString, std::string("tanh"), 1.0, 16.0, "tanh, sigmoid or linear"});
  }
  for (ParamSpec& s : common_params()) t.params.push_back(std::move(s));
  t.defaults.priority = 2;
  t.defaults.queue_capacity = 4;
  t.make = [kind, resources](const os::ParamSet& p) -> std::unique_ptr<os::Task> {
    network::Topology topology;
    topology.kind = kind;
    topology.inputs = static_cast<std::size_t>(p.integer("inputs"));
    topology.layers = parse_layers(p.string("layers"));
    std::vector<float> tau;
    double dt = 0.03;
    if (kind == Kind::kCtrnn) {
      tau = parse_list("tau", p.string("tau"), network::kMaxLayerSize);
      dt = seconds(p.duration("dt"));
    } else {
      auto a = network::parse_activation(p.string("activation"));
      if (!a) fail("activation: " + a.error());
      topology.activation = *a;
    }
    if (auto st = network::check(topology); !st) fail(st.error());
    auto weights = read_weights(p.string("weights"), *resources);
    if (!weights) fail("weights: " + weights.error());
    NetworkTaskOptions o = common_options(p);
    o.input_scale = parse_list("input_scale", p.string("input_scale"), network::kMaxInputs);
    return build(std::move(topology), *weights, tau, dt, std::move(o), resources);
  };
  return t;
}

os::TaskType described_type(const std::shared_ptr<const ControlResources>& resources) {
  os::TaskType t;
  t.name = "network";
  t.doc = "a network described in a text file (type, layers, weights, scales; docs/networks.md): same ports as mlp";
  t.params = {
      {"description", ParamType::kString, std::string(), 0.0, 1024.0,
       "the description (a reference the node resolves)"},
      {"dt", ParamType::kDuration, kernel::Duration(30ms), 1e-6, 10.0, "ctrnn: the Euler step per network step"},
  };
  for (ParamSpec& s : common_params()) {
    if (s.name == "weights") s.doc = "replaces the description's weights (numbers or a weight file); empty: keep them";
    if (s.name == "output_scale") s.doc = "used when the description gives none";
    t.params.push_back(std::move(s));
  }
  t.defaults.priority = 2;
  t.defaults.queue_capacity = 4;
  t.make = [resources](const os::ParamSet& p) -> std::unique_ptr<os::Task> {
    const std::string& reference = p.string("description");
    if (reference.empty()) fail("name the description: description=REFERENCE");
    if (!resources->read_program) fail("this node cannot read descriptions (no read_program)");
    auto text = resources->read_program(reference);
    if (!text) fail("description '" + shown(reference) + "': " + text.error());
    auto d = network::parse_description(*text);
    if (!d) fail("description '" + shown(reference) + "': " + d.error());
    std::vector<float> weights = d->weights.value_or(std::vector<float>{});
    if (!p.string("weights").empty()) {
      auto w = read_weights(p.string("weights"), *resources);
      if (!w) fail("weights: " + w.error());
      weights = std::move(w).value();
    }
    NetworkTaskOptions o = common_options(p);
    if (!d->input_scale.empty()) o.input_scale = d->input_scale;
    if (d->output_scale) o.output_scale = *d->output_scale;
    return build(d->topology, weights, d->tau, seconds(p.duration("dt")), std::move(o), resources);
  };
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
