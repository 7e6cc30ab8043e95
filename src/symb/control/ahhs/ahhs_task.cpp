#include "symb/control/ahhs/ahhs_task.hpp"

#include <algorithm>
#include <cmath>

namespace symb::control {

using kernel::Error;

kernel::Status check(const AhhsTaskOptions& o) {
  if (!std::isfinite(o.sensor_range) || o.sensor_range <= 0) return Error{"sensor_range must be a positive number"};
  if (!std::isfinite(o.actuator_scale) || o.actuator_scale <= 0)
    return Error{"actuator_scale must be a positive number"};
  if (o.warn_interval.count() < 0) return Error{"warn_interval must not be negative"};
  return {};
}

bool normalise_sensors(std::span<const float> raw, std::size_t needed, double range, std::vector<float>& out,
                       std::string& why) {
  if (raw.size() < needed) {
    why = "a sensor vector of " + std::to_string(raw.size()) + " values; the network reads " + std::to_string(needed);
    return false;
  }
  for (std::size_t k = 0; k < raw.size(); ++k)
    if (!std::isfinite(raw[k])) {
      why = "a sensor vector with a non-finite value at index " + std::to_string(k);
      return false;
    }
  out.resize(raw.size());
  for (std::size_t k = 0; k < raw.size(); ++k)
    out[k] = static_cast<float>(std::clamp(static_cast<double>(raw[k]) / range, 0.0, 1.0));
  return true;
}

kernel::Result<std::unique_ptr<AhhsTask>> AhhsTask::create(ahhs::Network network, AhhsTaskOptions options) {
  if (auto st = check(options); !st) return Error{"ahhs: " + st.error()};
  auto model = ahhs::Model::create(std::move(network));
  if (!model) return Error{"ahhs: " + model.error()};
  return std::unique_ptr<AhhsTask>(new AhhsTask(std::move(model).value(), options));
}

AhhsTask::AhhsTask(ahhs::Model model, AhhsTaskOptions options) : options_(options), model_(std::move(model)) {
  bind_parameters(options_);
}

std::vector<float> AhhsTask::levels(std::uint32_t compartment) const {
  std::lock_guard lock(mu_);
  if (compartment >= model_.compartments()) return {};
  auto l = model_.levels(compartment);
  return {l.begin(), l.end()};
}

std::vector<float> AhhsTask::actuators() const {
  std::lock_guard lock(mu_);
  auto a = model_.actuators();
  return {a.begin(), a.end()};
}

AhhsStats AhhsTask::stats() const { return counters_.snapshot(); }

void AhhsTask::ignore(const std::string& why) {
  counters_.ignored.bump();
  if (warning_.note(now(), options_.warn_interval)) {
    const std::uint64_t n = warning_.count();
    log(os::LogLevel::kWarn, std::to_string(n) + " message" + (n == 1 ? "" : "s") + " ignored, latest: " + why);
  }
}

void AhhsTask::on_message(const os::Message& m) {
  if (m.payload.blob || m.port != kAhhsSensorPort) {
    ignore(m.payload.blob ? "a blob (numbers expected)" : "a message on port " + std::to_string(m.port));
    return;
  }
  std::string why;
  if (!normalise_sensors(m.numbers(), model_.sensor_count(), options_.sensor_range, sensors_, why)) {
    ignore(why);
    return;
  }
  {
    std::lock_guard lock(mu_);
    model_.step(sensors_);
    counters_.steps.bump();
    const auto a = model_.actuators();
    out_.resize(a.size());
    for (std::size_t k = 0; k < a.size(); ++k) out_[k] = static_cast<float>(a[k] * options_.actuator_scale);
  }
  send(kAhhsActuatorPort, out_);
  if (probing()) {
    const std::uint32_t shown = std::min<std::uint32_t>(model_.compartments(), kMaxProbedCompartments);
    for (std::uint32_t c = 0; c < shown; ++c) probe("hormones/c" + std::to_string(c), model_.levels(c));
    probe("actuators", model_.actuators());
  }
}

}  // namespace symb::control
