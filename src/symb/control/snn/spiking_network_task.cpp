#include "symb/control/snn/spiking_network_task.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "symb/control/snn/network_layout.hpp"
#include "symb/control/snn/reference_network.hpp"
#include "symb/os/message.hpp"

namespace symb::control {

using kernel::Error;
using namespace std::chrono_literals;

namespace {

constexpr std::int64_t kNsPerMs = 1'000'000;

std::int64_t floor_div(std::int64_t a, std::int64_t b) { return a / b - ((a % b != 0) && ((a < 0) != (b < 0))); }

}  // namespace

kernel::Result<SpikingNetworkTask::Running> SpikingNetworkTask::make_running(snn::GrownNetwork network) {
  const std::size_t n = network.spec.neurons.size();
  for (const auto* channels : {&network.inputs, &network.outputs}) {
    if (channels->size() > static_cast<std::size_t>(snn::kMaxChannels))
      return Error{"at most " + std::to_string(snn::kMaxChannels) + " input and output channels"};
    for (const auto& c : *channels)
      for (std::uint32_t neuron : c)
        if (neuron >= n) return Error{"a channel names neuron " + std::to_string(neuron) + " of " + std::to_string(n)};
  }
  auto net = snn::SpikingNetwork::create(network.spec);
  if (!net) return Error{net.error()};
  Running r{std::move(net).value(), std::move(network), {}};
  r.output_channels_of.resize(n);
  for (std::size_t c = 0; c < r.grown.outputs.size(); ++c)
    for (std::uint32_t neuron : r.grown.outputs[c])
      r.output_channels_of[neuron].push_back(static_cast<std::uint32_t>(c));
  return r;
}

kernel::Result<std::unique_ptr<SpikingNetworkTask>> SpikingNetworkTask::create(snn::GrownNetwork network,
                                                                               SpikingNetworkTaskOptions options) {
  if (options.module > snn::kMaxModule)
    return Error{"module must be 0.." + std::to_string(snn::kMaxModule) + " (the AER module bits)"};
  if (!std::isfinite(options.pulse) || std::fabs(options.pulse) > snn::kMaxAbsWeight)
    return Error{"pulse must be a number within +-" + std::to_string(static_cast<int>(snn::kMaxAbsWeight))};
  if (options.max_catch_up < 1ms) return Error{"max_catch_up must be at least 1ms"};
  if (options.warn_interval.count() < 0) return Error{"warn_interval must not be negative"};
  auto running = make_running(std::move(network));
  if (!running) return Error{running.error()};
  if (options.thalamic && options.thalamic_excitatory > running->net.size())
    return Error{"thalamic_excitatory exceeds the network's size"};
  return std::unique_ptr<SpikingNetworkTask>(new SpikingNetworkTask(std::move(running).value(), std::move(options)));
}

SpikingNetworkTask::SpikingNetworkTask(Running running, SpikingNetworkTaskOptions options)
    : run_(std::move(running)), options_(std::move(options)), neurons_(run_.net.size()) {
  bind_parameters(options_);
  currents_.assign(snn::kMaxChannels, 0.0f);
}

SpikingNetworkStats SpikingNetworkTask::stats() const { return counters_.snapshot(); }

std::size_t SpikingNetworkTask::neurons() const {
  std::lock_guard lock(mu_);
  return neurons_;
}

void SpikingNetworkTask::ignore(const std::string& why) {
  counters_.ignored.bump();
  if (!warning_.note(now(), options_.warn_interval)) return;
  const std::uint64_t n = warning_.count();
  log(os::LogLevel::kWarn, std::to_string(n) + " message" + (n == 1 ? "" : "s") + " ignored, latest: " + why);
}

void SpikingNetworkTask::on_start() {
  if (!started_) {
    started_ = true;
    start_ = now();
  }
}

void SpikingNetworkTask::on_message(const os::Message& m) {
  if (const snn::AerPacket* packet = snn::aer_of(m)) {
    const std::int64_t now_us = now().count() / 1000;
    const std::int64_t start_us = start_.count() / 1000;
    std::uint64_t accepted = 0, late = 0, dropped = 0;
    for (const snn::AerEvent& e : packet->events) {
      const std::uint32_t channel = snn::aer_neuron(e.address);
      const std::int64_t at_us = snn::unwrap_us(e.timestamp_us, now_us);
      if (channel >= run_.grown.inputs.size() || at_us - now_us > kMaxLead.count() / 1000 ||
          queue_.size() >= kMaxQueuedEvents) {
        ++dropped;
        continue;
      }
      std::int64_t step = floor_div(at_us - start_us, 1000);
      if (step < step_) {
        step = step_;
        ++late;
      }
      queue_.push_back({step, channel});
      std::push_heap(queue_.begin(), queue_.end(), std::greater<>());
      ++accepted;
    }
    counters_.input_events.bump(accepted);
    counters_.late_events.bump(late);
    counters_.dropped_events.bump(dropped);
    return;
  }
  if (m.payload.blob) {
    ignore("a blob that is not an AER packet");
    return;
  }
  const std::span<const float> v = m.numbers();
  for (std::size_t k = 0; k < v.size(); ++k)
    if (!std::isfinite(v[k]) || std::fabs(v[k]) > snn::kMaxAbsBias) {
      ignore("an input current vector with a non-finite or huge value at index " + std::to_string(k));
      return;
    }
  std::fill(currents_.begin(), currents_.end(), 0.0f);
  std::copy_n(v.begin(), std::min(v.size(), currents_.size()), currents_.begin());
  counters_.current_vectors.bump();
}

void SpikingNetworkTask::run_step(std::vector<snn::AerEvent>& all, std::vector<snn::AerEvent>& outputs) {
  std::span<float> input = run_.net.input();
  const auto& inputs = run_.grown.inputs;
  for (std::size_t c = 0; c < inputs.size(); ++c)
    if (currents_[c] != 0.0f)
      for (std::uint32_t neuron : inputs[c]) input[neuron] += currents_[c];
  while (!queue_.empty() && queue_.front().step <= step_) {
    const std::uint32_t channel = queue_.front().channel;
    std::pop_heap(queue_.begin(), queue_.end(), std::greater<>());
    queue_.pop_back();
    if (channel < inputs.size())
      for (std::uint32_t neuron : inputs[channel]) input[neuron] += options_.pulse;
  }
  if (options_.thalamic) snn::add_thalamic_input(random(), input, options_.thalamic_excitatory);
  const std::span<const std::uint32_t> fired = run_.net.step();
  const kernel::Time at = start_ + kernel::Duration(step_ * kNsPerMs);
  const std::uint32_t ts = snn::aer_timestamp(at);
  const bool probe_spikes = probing();
  const auto at_ms = static_cast<float>(at.count() / kNsPerMs);
  for (std::uint32_t neuron : fired) {
    all.push_back({snn::aer_address(options_.module, neuron), ts});
    for (std::uint32_t c : run_.output_channels_of[neuron])
      outputs.push_back({snn::aer_address(options_.module, c), ts});
    if (probe_spikes) spike_probe_.insert(spike_probe_.end(), {at_ms, static_cast<float>(neuron)});
  }
  ++step_;
}

void SpikingNetworkTask::on_tick() {
  if (!started_) on_start();
  const std::int64_t target = (now() - start_).count() / kNsPerMs;
  std::int64_t skipped = 0;
  const std::int64_t cap = options_.max_catch_up.count() / kNsPerMs;
  if (target - step_ > cap) {
    skipped = target - step_ - cap;
    step_ = target - cap;
  }
  // Networks not grown on a grid (the built-in examples) have no layout to draw.
  if (layout_due_ && probing() && !run_.grown.x.empty()) {
    probe("layout", snn::layout_values(run_.grown));
    layout_due_ = false;
  }
  std::vector<snn::AerEvent> all, outputs;
  spike_probe_.clear();
  const std::int64_t first = step_;
  while (step_ < target) run_step(all, outputs);
  const std::int64_t ran = step_ - first;
  counters_.steps.bump(static_cast<std::uint64_t>(ran));
  counters_.spikes.bump(all.size());
  counters_.output_spikes.bump(outputs.size());
  counters_.skipped_ms.bump(static_cast<std::uint64_t>(skipped));
  if (ran > 0 && probing()) {
    if (!spike_probe_.empty()) probe("spikes", spike_probe_);
    probe("rate", {static_cast<float>(static_cast<double>(all.size()) * 1000.0 /
                                      (static_cast<double>(run_.net.size()) * static_cast<double>(ran)))});
  }
  if (!all.empty()) send(kAllSpikesPort, snn::aer_payload(std::move(all)));
  if (!outputs.empty()) send(kOutputSpikesPort, snn::aer_payload(std::move(outputs)));
}

kernel::Status SpikingNetworkTask::replace(snn::GrownNetwork network) {
  auto running = make_running(std::move(network));
  if (!running) return Error{running.error()};
  if (options_.thalamic && options_.thalamic_excitatory > running->net.size())
    return Error{"thalamic_excitatory exceeds the new network's size"};
  run_ = std::move(running).value();
  layout_due_ = true;
  counters_.replacements.bump();
  std::lock_guard lock(mu_);
  neurons_ = run_.net.size();
  return {};
}

kernel::Status SpikingNetworkTask::on_parameter_changed(std::string_view name) {
  if (name == "genome" || name == "seed") {
    if (!options_.grow) return Error{"this network was not grown from a genome"};
    auto grown = options_.grow(options_.genome, options_.seed);
    if (!grown) return Error{std::string(name) + ": " + grown.error()};
    if (auto st = replace(std::move(grown).value()); !st) return Error{std::string(name) + ": " + st.error()};
  }
  if (name == "pulse" && (!std::isfinite(options_.pulse) || std::fabs(options_.pulse) > snn::kMaxAbsWeight))
    return Error{"pulse out of range"};
  return {};
}

}  // namespace symb::control
