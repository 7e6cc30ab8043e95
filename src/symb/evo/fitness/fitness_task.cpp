#include "symb/evo/fitness/fitness_task.hpp"

#include <string>
#include <variant>

#include "symb/kernel/counter.hpp"
#include "symb/os/message.hpp"

namespace symb::evo {

FitnessStats FitnessTask::stats() const {
  return {sum_.load(std::memory_order_relaxed), steps_.load(), commands_.load(), ignored_.load()};
}

double FitnessTask::mean() const {
  const FitnessStats s = stats();
  return s.steps == 0 ? 0.0 : s.sum / static_cast<double>(s.steps);
}

void FitnessTask::on_message(const os::Message& m) {
  const auto values = m.numbers();
  if (m.port != 0 || m.payload.blob || values.size() < 2) {
    ignored_.bump();
    return;
  }
  if (values.size() == 2) {
    left_ = values[0], right_ = values[1];
    command_time_ = now();
    have_command_ = true;
    commands_.bump();
    return;
  }
  const bool fresh = have_command_ && now() - command_time_ <= options_.command_timeout;
  const double step = fitness_step(options_.formula, fresh ? left_ : 0.0, fresh ? right_ : 0.0, values);
  const double sum = sum_.load(std::memory_order_relaxed) + step;
  const std::uint64_t steps = steps_.load() + 1;
  sum_.store(sum, std::memory_order_relaxed);
  steps_.bump();
  float out[4] = {static_cast<float>(sum), static_cast<float>(steps), static_cast<float>(step), 0.0f};
  probe("fitness", std::span<const float>(out, 3));
  window_sum_ += step;
  if (++window_steps_ < options_.every) return;
  // One step: [sum, steps, step]. More (every > 1, or the rest of a window when `every` was
  // lowered meanwhile): [sum, steps, window sum, window steps]. No step goes unreported.
  std::size_t n = 3;
  if (window_steps_ > 1) {
    out[2] = static_cast<float>(window_sum_);
    out[3] = static_cast<float>(window_steps_);
    n = 4;
  }
  window_sum_ = 0;
  window_steps_ = 0;
  send(0, std::span<const float>(out, n));
}

kernel::Status FitnessTask::on_parameter_changed(std::string_view name) {
  if (name == "reset" && options_.reset) {
    sum_.store(0, std::memory_order_relaxed);
    steps_.reset();
    window_sum_ = 0;
    window_steps_ = 0;
    options_.reset = false;
  }
  return {};
}

}  // namespace symb::evo
