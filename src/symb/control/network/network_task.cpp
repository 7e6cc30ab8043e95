#include "symb/control/network/network_task.hpp"

#include <algorithm>
#include <cmath>

#include "symb/control/control_task_types.hpp"
#include "symb/control/network/description.hpp"
#include "symb/os/message.hpp"

namespace symb::control {

using kernel::Error;

namespace {

bool starts_like_number(std::string_view s) {
  const std::size_t i = s.find_first_not_of(" \t\r\n");
  if (i == std::string_view::npos) return true;  // blank: no weights
  const char c = s[i];
  return (c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.' || c == '#';
}

kernel::Status check_scale(std::span<const float> scale, std::size_t inputs) {
  if (scale.size() != 1 && scale.size() != inputs)
    return Error{"input_scale takes one factor or one per input (" + std::to_string(inputs) + "), got " +
                 std::to_string(scale.size())};
  for (float f : scale)
    if (!std::isfinite(f)) return Error{"input_scale factors must be finite"};
  return {};
}

}  // namespace

kernel::Result<NetworkOutput> parse_network_output(std::string_view text) {
  if (text == "wheels") return NetworkOutput::kWheels;
  if (text == "raw") return NetworkOutput::kRaw;
  if (text == "both") return NetworkOutput::kBoth;
  return Error{"output must be wheels, raw or both, got '" + shown_reference(text) + "'"};
}

kernel::Result<std::vector<float>> read_weights(std::string_view value, const ControlResources& resources) {
  if (starts_like_number(value)) return network::parse_numbers(value);
  const std::string reference(value);
  if (!resources.read_program)
    return Error{"cannot read weight file '" + shown_reference(reference) + "' (no read_program)"};
  auto text = resources.read_program(reference);
  if (!text) return Error{"weight file '" + shown_reference(reference) + "': " + text.error()};
  auto numbers = network::parse_numbers(*text);
  if (!numbers) return Error{"weight file '" + shown_reference(reference) + "': " + numbers.error()};
  return numbers;
}

kernel::Result<std::unique_ptr<NetworkTask>> NetworkTask::create(network::Network net, NetworkTaskOptions options,
                                                                 std::shared_ptr<const ControlResources> resources) {
  if (auto st = check_scale(options.input_scale, net.input_count()); !st) return Error{st.error()};
  if (!std::isfinite(options.output_scale) || options.output_scale <= 0)
    return Error{"output_scale must be a positive number"};
  if (!std::isfinite(options.speed_limit) || options.speed_limit <= 0)
    return Error{"speed_limit must be a positive number"};
  if (options.output != NetworkOutput::kRaw && net.output_count() < 2)
    return Error{"wheel output needs 2 or more network outputs (or output=raw)"};
  if (net.output_count() > os::Payload::kInlineValues)
    return Error{"at most " + std::to_string(os::Payload::kInlineValues) +
                 " outputs (one message carries the output vector)"};
  if (options.warn_interval.count() < 0) return Error{"warn_interval must not be negative"};
  return std::unique_ptr<NetworkTask>(new NetworkTask(std::move(net), std::move(options), std::move(resources)));
}

NetworkTask::NetworkTask(network::Network net, NetworkTaskOptions options,
                         std::shared_ptr<const ControlResources> resources)
    : net_(std::move(net)),
      options_(std::move(options)),
      resources_(std::move(resources)),
      genome_size_(net_.genome_size()),
      centred_(net_.topology().kind == network::Kind::kCtrnn ||
               net_.topology().activation == network::Activation::kSigmoid),
      scaled_(net_.input_count(), 0.0f),
      genome_copy_(net_.genome().begin(), net_.genome().end()),
      outputs_copy_(net_.outputs().begin(), net_.outputs().end()) {
  bind_parameters(options_);
  bind_parameters(model_params_);
  for (std::size_t l = 0; l < net_.layer_count(); ++l) channels_.push_back("activations/" + net_.layer_name(l));
}

NetworkStats NetworkTask::stats() const { return counters_.snapshot(); }

std::vector<float> NetworkTask::genome() const {
  std::lock_guard lock(mu_);
  return genome_copy_;
}

std::vector<float> NetworkTask::last_outputs() const {
  std::lock_guard lock(mu_);
  return outputs_copy_;
}

void NetworkTask::ignore(const std::string& why) {
  counters_.ignored.bump();
  if (!warning_.note(now(), options_.warn_interval)) return;
  const std::uint64_t n = warning_.count();
  log(os::LogLevel::kWarn, std::to_string(n) + " message" + (n == 1 ? "" : "s") + " ignored, latest: " + why);
}

float NetworkTask::wheel(float raw, std::uint64_t& clamped) const {
  double v = options_.output_scale * (centred_ ? 2.0 * raw - 1.0 : static_cast<double>(raw));
  if (!std::isfinite(v)) {
    ++clamped;
    return 0.0f;
  }
  if (v > options_.speed_limit || v < -options_.speed_limit) {
    ++clamped;
    v = std::clamp(v, -options_.speed_limit, options_.speed_limit);
  }
  return static_cast<float>(v);
}

void NetworkTask::on_message(const os::Message& m) {
  if (m.port != options_.input_port) {
    ignore("a message on port " + std::to_string(m.port) + " (inputs on " + std::to_string(options_.input_port) + ")");
    return;
  }
  if (m.payload.blob) {
    ignore("a blob (an input vector of numbers expected)");
    return;
  }
  const std::span<const float> v = m.numbers();
  if (v.size() != scaled_.size()) {
    ignore("an input vector of " + std::to_string(v.size()) + " values; the network takes " +
           std::to_string(scaled_.size()));
    return;
  }
  for (std::size_t k = 0; k < v.size(); ++k) {
    if (!std::isfinite(v[k])) {
      ignore("an input vector with a non-finite value at index " + std::to_string(k));
      return;
    }
    const float scale = options_.input_scale.size() == 1 ? options_.input_scale[0] : options_.input_scale[k];
    scaled_[k] = v[k] * scale;
  }
  const std::span<const float> out = net_.step(scaled_);
  std::uint64_t clamped = 0;
  float left = 0, right = 0;
  const bool wheels = options_.output != NetworkOutput::kRaw;
  if (wheels) {
    left = wheel(out[0], clamped);
    right = wheel(out[1], clamped);
  }
  counters_.inputs.bump();
  counters_.steps.bump();
  counters_.clamped.bump(clamped);
  {
    std::lock_guard lock(mu_);
    outputs_copy_.assign(out.begin(), out.end());
  }
  if (probing()) {
    for (std::size_t l = 0; l < net_.layer_count(); ++l) probe(channels_[l], net_.layer(l));
    probe("outputs", out);
  }
  if (wheels) send(kNetworkWheelPort, {left, right});
  if (options_.output == NetworkOutput::kRaw) send(kNetworkWheelPort, out);
  if (options_.output == NetworkOutput::kBoth) send(kRawOutputPort, out);
}

kernel::Status NetworkTask::on_parameter_changed(std::string_view name) {
  if (name == "weights") {
    auto weights = read_weights(model_params_.weights, resources_ ? *resources_ : ControlResources{});
    if (!weights) return Error{"weights: " + weights.error()};
    if (weights->empty()) weights.value().assign(genome_size_, 0.0f);
    if (auto st = net_.set_genome(*weights); !st) return Error{"weights: " + st.error()};
    {
      std::lock_guard lock(mu_);
      genome_copy_ = *weights;
    }
    counters_.genomes.bump();
    return {};
  }
  if (name == "input_scale") return check_scale(options_.input_scale, net_.input_count());
  if (name == "tau") {
    if (net_.topology().kind != network::Kind::kCtrnn) return Error{"tau is for ctrnn networks only"};
    auto tau = network::parse_numbers(model_params_.tau, network::kMaxLayerSize);
    if (!tau) return Error{"tau: " + tau.error()};
    return net_.set_time_constants(*tau);
  }
  if (name == "dt") {
    if (net_.topology().kind != network::Kind::kCtrnn) return Error{"dt is for ctrnn networks only"};
    return net_.set_step(std::chrono::duration<double>(model_params_.dt).count());
  }
  return {};
}

}  // namespace symb::control
