#include "symb/evo/fitness_task.hpp"

#include <string>
#include <variant>

#include "symb/os/message.hpp"

namespace symb::evo {

FitnessStats FitnessTask::stats() const {
  std::lock_guard lock(mu_);
  return stats_;
}

double FitnessTask::mean() const {
  std::lock_guard lock(mu_);
  return stats_.steps == 0 ? 0.0 : stats_.sum / static_cast<double>(stats_.steps);
}

void FitnessTask::on_message(const os::Message& m) {
  const auto values = m.numbers();
  if (m.port != 0 || m.payload.blob || values.size() < 2) {
    std::lock_guard lock(mu_);
    ++stats_.ignored;
    return;
  }
  if (values.size() == 2) {
    left_ = values[0], right_ = values[1];
    command_time_ = now();
    have_command_ = true;
    std::lock_guard lock(mu_);
    ++stats_.commands;
    return;
  }
  const bool fresh = have_command_ && now() - command_time_ <= options_.command_timeout;
  const double step = fitness_step(options_.formula, fresh ? left_ : 0.0, fresh ? right_ : 0.0, values);
  float out[3];
  {
    std::lock_guard lock(mu_);
    stats_.sum += step;
    ++stats_.steps;
    out[0] = static_cast<float>(stats_.sum);
    out[1] = static_cast<float>(stats_.steps);
    out[2] = static_cast<float>(step);
  }
  send(0, std::span<const float>(out, 3));
  probe("fitness", std::span<const float>(out, 3));
}

kernel::Status FitnessTask::on_parameter(std::string_view name, const os::ParamValue& value) {
  if (name == "formula") {
    const auto* text = std::get_if<std::string>(&value);
    const auto f = text ? parse_fitness_formula(*text) : std::nullopt;
    if (!f) return kernel::Error{"formula: floreano_mondada, one_plus_one or liolib"};
    options_.formula = *f;
    return {};
  }
  if (name == "reset") {
    if (const auto* b = std::get_if<bool>(&value); b && *b) {
      std::lock_guard lock(mu_);
      stats_.sum = 0;
      stats_.steps = 0;
    }
    return {};
  }
  if (name == "command_timeout") {
    if (const auto* d = std::get_if<kernel::Duration>(&value)) {
      options_.command_timeout = *d;
      return {};
    }
  }
  return kernel::Error{"fitness: no runtime parameter '" + std::string(name) + "'"};
}

}  // namespace symb::evo
