#include "symb/control/ahhs/model.hpp"

#include <algorithm>

namespace symb::control::ahhs {

kernel::Result<Model> Model::create(Network network) {
  if (auto st = validate(network); !st) return kernel::Error{st.error()};
  return Model(std::move(network));
}

Model::Model(Network network) : network_(std::move(network)) {
  stride_ = network_.hormones.size();
  sensor_count_ = network_.sensor_count();
  neighbours_ = neighbour_lists(network_);
  const std::uint32_t nc = network_.compartments;
  actuators_in_.resize(nc);
  for (const Placement& a : network_.actuators) actuators_in_[a.compartment].push_back(a.index);
  for (auto& l : actuators_in_) std::sort(l.begin(), l.end());
  std::vector<std::int32_t> sensor_home(kMaxSensorIndex, -1);
  for (const Placement& s : network_.sensors) sensor_home[s.index] = static_cast<std::int32_t>(s.compartment);
  std::vector<std::int32_t> actuator_home(network_.actuators.size(), -1);
  for (const Placement& a : network_.actuators) actuator_home[a.index] = static_cast<std::int32_t>(a.compartment);
  rules_in_.resize(nc);
  for (std::uint32_t k = 0; k < network_.rules.size(); ++k) {
    const Rule& r = network_.rules[k];
    std::int32_t home = r.compartment;
    if (r.kind == RuleKind::kSensor) home = sensor_home[r.source];
    if (r.kind == RuleKind::kActuator) home = actuator_home[r.target];
    if (home == kEveryCompartment)
      everywhere_.push_back(k);
    else
      rules_in_[static_cast<std::uint32_t>(home)].push_back(k);
  }
  for (const Hormone& h : network_.hormones) {
    base_.push_back(h.base);
    decay_.push_back(h.decay);
    diffusion_.push_back(h.diffusion);
    min_.push_back(h.min);
    max_.push_back(h.max);
  }
  levels_.resize(static_cast<std::size_t>(nc) * stride_);
  local_.resize(levels_.size());
  actuators_.resize(network_.actuators.size());
  reset();
}

void Model::reset() {
  for (std::size_t c = 0; c < network_.compartments; ++c)
    for (std::size_t h = 0; h < stride_; ++h) levels_[c * stride_ + h] = network_.hormones[h].start;
  std::fill(actuators_.begin(), actuators_.end(), 0.0f);
}

double Model::total(std::size_t h) const {
  double sum = 0;
  for (std::size_t c = 0; c < network_.compartments; ++c) sum += levels_[c * stride_ + h];
  return sum;
}

void Model::apply_rule(const Rule& r, const float* row, std::span<const float> sensors, float* delta,
                       std::span<float> actuators) const {
  switch (r.kind) {
    case RuleKind::kSensor: {
      const float s = r.source < sensors.size() ? sensors[r.source] : 0.0f;
      const float t = trigger(s, r.centre, r.width);
      if (t != 0.0f) delta[r.target] += t * (r.dependent * s + r.fixed);
      break;
    }
    case RuleKind::kHormone: {
      // The published intent: hormone `source` regulates hormone `target` (the 2009 code's
      // direct path fed the term back into the source's own change; see docs/ahhs.md, pitfall 1).
      const float x = row[r.source];
      const float t = trigger(x, r.centre, r.width);
      if (t != 0.0f) delta[r.target] += t * (r.dependent * x + r.fixed);
      break;
    }
    case RuleKind::kNonlinear: {
      const float x = row[r.source];
      const float t = trigger(x, r.centre, r.width);
      if (t != 0.0f) delta[r.target] += t * (r.dependent * x * row[r.target] + r.fixed);
      break;
    }
    case RuleKind::kActuator: {
      const float x = row[r.source];
      const float t = trigger(x, r.centre, r.width);
      if (t != 0.0f) actuators[r.target] += t * (r.dependent * x + r.fixed);
      break;
    }
  }
}

void Model::local_update(std::uint32_t c, std::span<const float> row, std::span<const float> sensors,
                         std::span<float> out, std::span<float> actuators) const {
  float* delta = out.data();
  for (std::size_t h = 0; h < stride_; ++h) delta[h] = base_[h] - decay_[h] * row[h];
  for (std::uint32_t k : rules_in_[c]) apply_rule(network_.rules[k], row.data(), sensors, delta, actuators);
  for (std::uint32_t k : everywhere_) apply_rule(network_.rules[k], row.data(), sensors, delta, actuators);
  for (std::size_t h = 0; h < stride_; ++h) out[h] = std::clamp(row[h] + delta[h], min_[h], max_[h]);
}

void Model::diffuse(std::uint32_t c, std::span<const float> own, std::span<const float* const> neighbour_rows,
                    std::span<float> out) const {
  const std::size_t nn = neighbours_[c].size();
  for (std::size_t h = 0; h < stride_; ++h) {
    const float x = own[h];
    if (diffusion_[h] == 0.0f || nn == 0) {
      out[h] = x;
      continue;
    }
    float flow = 0;
    for (std::size_t k = 0; k < nn; ++k) flow += x - neighbour_rows[k][h];
    out[h] = std::clamp(x - diffusion_[h] * flow, min_[h], max_[h]);
  }
}

void Model::step(std::span<const float> sensors) {
  std::fill(actuators_.begin(), actuators_.end(), 0.0f);
  const std::uint32_t nc = network_.compartments;
  for (std::uint32_t c = 0; c < nc; ++c)
    local_update(c, {&levels_[c * stride_], stride_}, sensors, {&local_[c * stride_], stride_}, actuators_);
  for (std::uint32_t c = 0; c < nc; ++c) {
    const auto& nb = neighbours_[c];
    scratch_.resize(nb.size());
    for (std::size_t k = 0; k < nb.size(); ++k) scratch_[k] = &local_[nb[k] * stride_];
    diffuse(c, {&local_[c * stride_], stride_}, scratch_, {&levels_[c * stride_], stride_});
  }
  for (float& a : actuators_) a = std::clamp(a, -1.0f, 1.0f);
}

}  // namespace symb::control::ahhs
