#include "symb/control/ahhs/ahhs_compartment_task.hpp"

#include <algorithm>
#include <cmath>

namespace symb::control {

using kernel::Error;

kernel::Result<std::unique_ptr<AhhsCompartmentTask>> AhhsCompartmentTask::create(ahhs::Network network,
                                                                                 std::uint32_t compartment,
                                                                                 AhhsTaskOptions options) {
  if (auto st = check(options); !st) return Error{"ahhs_compartment: " + st.error()};
  auto model = ahhs::Model::create(std::move(network));
  if (!model) return Error{"ahhs_compartment: " + model.error()};
  if (compartment >= model->compartments())
    return Error{"ahhs_compartment: compartment " + std::to_string(compartment) + " is not in the network (it has " +
                 std::to_string(model->compartments()) + ")"};
  return std::unique_ptr<AhhsCompartmentTask>(new AhhsCompartmentTask(std::move(model).value(), compartment, options));
}

AhhsCompartmentTask::AhhsCompartmentTask(ahhs::Model model, std::uint32_t compartment, AhhsTaskOptions options)
    : model_(std::move(model)), compartment_(compartment), options_(options) {
  bind_parameters(options_);
  neighbours_ = model_.neighbours(compartment_);
  held_.resize(neighbours_.size());
  const auto start = model_.levels(compartment_);
  row_.assign(start.begin(), start.end());
  local_.resize(row_.size());
  actuators_.assign(model_.actuator_count(), 0.0f);
  rows_.resize(neighbours_.size());
  shown_ = row_;
}

std::vector<float> AhhsCompartmentTask::levels() const {
  std::lock_guard lock(mu_);
  return shown_;
}

AhhsCompartmentStats AhhsCompartmentTask::stats() const { return counters_.snapshot(); }

void AhhsCompartmentTask::ignore(const std::string& why) {
  counters_.ignored.bump();
  if (warning_.note(now(), options_.warn_interval)) {
    const std::uint64_t n = warning_.count();
    log(os::LogLevel::kWarn, std::to_string(n) + " message" + (n == 1 ? "" : "s") + " ignored, latest: " + why);
  }
}

void AhhsCompartmentTask::on_message(const os::Message& m) {
  if (m.payload.blob) {
    ignore("a blob (numbers expected)");
    return;
  }
  const auto v = m.numbers();
  if (m.port == kAhhsSensorPort) {
    std::string why;
    if (!normalise_sensors(v, model_.sensor_count(), options_.sensor_range, sensors_, why)) {
      ignore(why);
      return;
    }
    if (awaiting_) finish_step(true);
    std::fill(actuators_.begin(), actuators_.end(), 0.0f);
    model_.local_update(compartment_, row_, sensors_, local_, actuators_);
    message_.assign(1, static_cast<float>(compartment_));
    message_.insert(message_.end(), local_.begin(), local_.end());
    send(kAhhsLevelsPort, message_);
    const auto& mine = model_.actuators_in(compartment_);
    if (!mine.empty()) {
      message_.clear();
      for (std::uint32_t a : mine) {
        message_.push_back(static_cast<float>(a));
        message_.push_back(std::clamp(actuators_[a], -1.0f, 1.0f));
      }
      send(kAhhsActuatorPairsPort, message_);
      if (probing()) {
        std::vector<float> shown;
        for (std::uint32_t a : mine) shown.push_back(std::clamp(actuators_[a], -1.0f, 1.0f));
        probe("actuators", shown);
      }
    }
    counters_.steps.bump();
    awaiting_ = true;
    try_finish();
    return;
  }
  if (m.port == kAhhsLevelsPort) {
    const std::size_t nh = model_.hormones();
    if (v.size() != nh + 1 || !(v[0] >= 0) || v[0] != std::floor(v[0]) || v[0] >= 1e9f) {
      ignore("a level message must be [compartment id, " + std::to_string(nh) + " levels], got " +
             std::to_string(v.size()) + " value(s)");
      return;
    }
    for (float x : v)
      if (!std::isfinite(x)) {
        ignore("a level message with a non-finite value");
        return;
      }
    const auto id = static_cast<std::uint32_t>(v[0]);
    const auto it = std::lower_bound(neighbours_.begin(), neighbours_.end(), id);
    if (it == neighbours_.end() || *it != id) {
      counters_.foreign_levels.bump();
      return;
    }
    auto& q = held_[static_cast<std::size_t>(it - neighbours_.begin())];
    if (q.size() >= kMaxHeldLevels) q.pop_front();
    q.emplace_back(v.begin() + 1, v.end());
    try_finish();
    return;
  }
  ignore("a message on port " + std::to_string(m.port) + " (sensors on 0, levels on 1)");
}

void AhhsCompartmentTask::try_finish() {
  if (!awaiting_) return;
  for (const auto& q : held_)
    if (q.empty()) return;
  finish_step(false);
}

void AhhsCompartmentTask::finish_step(bool forced) {
  // A missing neighbour is treated as having this compartment's own levels: no exchange with it.
  std::uint64_t missing = 0;
  for (std::size_t k = 0; k < neighbours_.size(); ++k) {
    if (held_[k].empty()) {
      rows_[k] = local_.data();
      ++missing;
    } else {
      rows_[k] = held_[k].front().data();
    }
  }
  model_.diffuse(compartment_, local_, rows_, row_);
  for (auto& q : held_)
    if (!q.empty()) q.pop_front();
  awaiting_ = false;
  {
    std::lock_guard lock(mu_);
    shown_ = row_;
  }
  if (forced || missing > 0)
    counters_.missed_exchanges.bump(missing);
  else
    counters_.exchanges.bump();
  probe("hormones/c" + std::to_string(compartment_), row_);
}

// --- mixer ---------------------------------------------------------------------------------------

kernel::Result<std::unique_ptr<AhhsMixerTask>> AhhsMixerTask::create(std::size_t actuators, AhhsTaskOptions options) {
  if (auto st = check(options); !st) return Error{"ahhs_mixer: " + st.error()};
  if (actuators == 0 || actuators > ahhs::kMaxActuators)
    return Error{"ahhs_mixer: actuators must be 1 to " + std::to_string(ahhs::kMaxActuators)};
  return std::unique_ptr<AhhsMixerTask>(new AhhsMixerTask(actuators, options));
}

AhhsMixerTask::AhhsMixerTask(std::size_t actuators, AhhsTaskOptions options)
    : options_(options), values_(actuators, 0.0f), have_(actuators, false), last_(actuators, 0.0f) {
  bind_parameters(options_);
}

std::vector<float> AhhsMixerTask::last() const {
  std::lock_guard lock(mu_);
  return last_;
}
std::uint64_t AhhsMixerTask::sent() const { return sent_.load(); }
std::uint64_t AhhsMixerTask::flushed() const { return flushed_.load(); }

void AhhsMixerTask::flush() {
  out_.resize(values_.size());
  for (std::size_t k = 0; k < values_.size(); ++k) out_[k] = static_cast<float>(values_[k] * options_.actuator_scale);
  {
    std::lock_guard lock(mu_);
    last_ = values_;
  }
  sent_.bump();
  if (have_count_ < values_.size()) flushed_.bump();
  std::fill(have_.begin(), have_.end(), false);
  have_count_ = 0;
  send(kAhhsActuatorPort, out_);
  probe("actuators", values_);
}

void AhhsMixerTask::on_message(const os::Message& m) {
  const auto v = m.numbers();
  bool ok = !m.payload.blob && m.port == kAhhsActuatorPairsPort && !v.empty() && v.size() % 2 == 0;
  for (std::size_t k = 0; ok && k < v.size(); k += 2)
    ok = v[k] >= 0 && v[k] < static_cast<float>(values_.size()) && v[k] == std::floor(v[k]) && std::isfinite(v[k + 1]);
  if (!ok) {
    if (warning_.note(now(), options_.warn_interval)) {
      const std::uint64_t n = warning_.count();
      log(os::LogLevel::kWarn, std::to_string(n) + " message" + (n == 1 ? "" : "s") + " ignored, latest on port " +
                                   std::to_string(m.port) + " (expected [actuator index, value, ...] on port 2)");
    }
    return;
  }
  for (std::size_t k = 0; k < v.size(); k += 2) {
    const auto i = static_cast<std::size_t>(v[k]);
    if (have_[i]) flush();
    values_[i] = std::clamp(v[k + 1], -1.0f, 1.0f);
    have_[i] = true;
    ++have_count_;
  }
  if (have_count_ == values_.size()) flush();
}

}  // namespace symb::control
