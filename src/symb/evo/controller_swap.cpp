#include "symb/evo/controller_swap.hpp"

#include <cmath>
#include <utility>

#include "symb/control/network/description.hpp"
#include "symb/control/network/network.hpp"
#include "symb/os/node.hpp"

namespace symb::evo {

kernel::Status check(const ControllerSwapOptions& o, const std::string& who) {
  if (o.evaluation.count() <= 0) return kernel::Error{who + ": evaluation must be positive"};
  if (o.recovery.count() < 0) return kernel::Error{who + ": recovery must not be negative"};
  for (const std::string* n : {&o.controller, &o.sensor, &o.actuator, &o.fitness})
    if (!os::is_valid_name(*n)) return kernel::Error{who + ": '" + *n + "' cannot name a task"};
  if (!os::is_valid_name(o.controller_type))
    return kernel::Error{who + ": '" + o.controller_type + "' cannot name a task type"};
  auto params = os::parse_param_assignments(o.controller_params);
  if (!params) return kernel::Error{who + ": controller parameters: " + params.error()};
  for (const auto& a : *params)
    if (a.name == "weights") return kernel::Error{who + ": controller parameters: weights are the genome's"};
  return {};
}

kernel::Result<std::size_t> mlp_genome_size(std::int64_t inputs, const std::string& layers,
                                            const std::string& activation) {
  namespace net = control::network;
  net::Topology topology;
  topology.kind = net::Kind::kMlp;
  if (inputs < 1 || inputs > static_cast<std::int64_t>(net::kMaxInputs))
    return kernel::Error{"inputs: must be 1.." + std::to_string(net::kMaxInputs)};
  topology.inputs = static_cast<std::size_t>(inputs);
  auto sizes = net::parse_numbers(layers, net::kMaxLayers);
  if (!sizes) return kernel::Error{"layers: " + sizes.error()};
  topology.layers.clear();
  for (float v : *sizes) {
    if (!(v >= 1 && v <= static_cast<float>(net::kMaxLayerSize)) || v != static_cast<float>(static_cast<int>(v)))
      return kernel::Error{"layers: sizes are whole numbers 1.." + std::to_string(net::kMaxLayerSize)};
    topology.layers.push_back(static_cast<std::size_t>(v));
  }
  auto a = net::parse_activation(activation);
  if (!a) return kernel::Error{"activation: " + a.error()};
  topology.activation = *a;
  if (auto st = net::check(topology); !st) return kernel::Error{st.error()};
  return net::genome_size(topology);
}

kernel::Status check_mlp_genes(std::size_t genes, std::int64_t inputs, const std::string& layers,
                               const std::string& activation) {
  auto needed = mlp_genome_size(inputs, layers, activation);
  if (!needed) return kernel::Error{needed.error()};
  if (genes != *needed)
    return kernel::Error{"genes: " + std::to_string(genes) + " genes, but the mlp (inputs=" + std::to_string(inputs) +
                         " layers=\"" + layers + "\") has " + std::to_string(*needed) + " weights and biases"};
  return {};
}

std::string mlp_params_text(std::int64_t inputs, const std::string& layers, const std::string& activation) {
  return "inputs=" + std::to_string(inputs) + " layers=\"" + layers + "\" activation=" + activation;
}

ControllerSwap::ControllerSwap(ControllerSwapOptions options, std::string who)
    : options_(std::move(options)), who_(std::move(who)) {
  // check() has accepted them; an unparseable text leaves no extra parameters.
  if (auto p = os::parse_param_assignments(options_.controller_params)) params_ = std::move(p).value();
}

kernel::Result<bool> ControllerSwap::set_up(os::Node& node, os::TaskId evolution) {
  const auto sensor = node.find(options_.sensor), actuator = node.find(options_.actuator),
             fitness = node.find(options_.fitness);
  if (!sensor || !actuator || !fitness) return false;
  if (auto h = node.hook(*fitness, evolution); !h)
    return kernel::Error{who_ + ": cannot hook '" + options_.fitness + "': " + h.error()};
  sensor_ = *sensor, actuator_ = *actuator, fitness_ = *fitness;
  return true;
}

kernel::Status ControllerSwap::swap(os::Node& node, const RealGenome& genome, kernel::Time now) {
  if (have_controller_) {
    (void)node.remove(controller_);  // gone already (removed by someone else) is fine
    have_controller_ = false;
  } else if (auto existing = node.find(options_.controller)) {
    (void)node.remove(*existing);  // the scenario's own controller: the first candidate replaces it
  }
  std::vector<os::ParamAssignment> assignments = params_;
  assignments.push_back({"weights", weights_text(genome), 1});
  auto created = node.create(options_.controller_type, options_.controller, assignments);
  if (!created) return kernel::Error{who_ + ": cannot create the candidate controller: " + created.error()};
  controller_ = *created;
  have_controller_ = true;
  const os::TaskId links[3][2] = {{sensor_, controller_}, {controller_, actuator_}, {controller_, fitness_}};
  for (const auto& link : links)
    if (auto h = node.hook(link[0], link[1]); !h)
      return kernel::Error{who_ + ": cannot hook the candidate controller: " + h.error()};
  started_ = now;
  counted_sum_ = 0;
  counted_steps_ = 0;
  return {};
}

std::optional<double> ControllerSwap::feed(const os::Message& m, kernel::Time now) {
  if (!have_controller_ || m.source != fitness_) return std::nullopt;
  const auto v = m.numbers();
  if (v.size() < 2 || !std::isfinite(v[0])) return std::nullopt;
  const double step = v.size() >= 3 ? static_cast<double>(v[2]) : static_cast<double>(v[0]) - last_sum_;
  // [sum, steps, window sum, N]: a report of N steps (fitness task's `every`).
  const std::uint64_t steps = v.size() >= 4 && v[3] >= 1 && v[3] <= 1e6 ? static_cast<std::uint64_t>(v[3]) : 1;
  last_sum_ = v[0];
  if (now < started_ + options_.recovery) return std::nullopt;  // recovery: not counted
  if (std::isfinite(step)) {
    counted_sum_ += step;
    counted_steps_ += steps;
  }
  if (now < started_ + options_.recovery + options_.evaluation) return std::nullopt;
  return counted_steps_ == 0 ? 0.0 : counted_sum_ / static_cast<double>(counted_steps_);
}

}  // namespace symb::evo
