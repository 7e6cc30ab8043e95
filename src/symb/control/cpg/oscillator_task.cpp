#include "symb/control/cpg/oscillator_task.hpp"

#include <cmath>
#include <numbers>
#include <string>

namespace symb::control::cpg {

OscillatorParams OscillatorTask::params_of(const OscillatorOptions& o) {
  return OscillatorParams{.id = static_cast<std::int32_t>(o.id),
                          .frequency = o.frequency,
                          .amplitude = o.amplitude,
                          .offset = o.offset,
                          .coupling = o.coupling,
                          .lag = o.lag,
                          .neighbour_timeout = kernel::to_seconds(o.neighbour_timeout),
                          .initial_phase = o.initial_phase};
}

OscillatorTask::OscillatorTask(OscillatorOptions options)
    : o_(options), oscillator_(params_of(options)), phase_(oscillator_.phase()) {
  bind_parameters(o_);
}

double OscillatorTask::seconds(kernel::Time t) { return kernel::to_seconds(t); }

void OscillatorTask::on_start() {
  if (o_.random_phase) oscillator_.set_phase(random().uniform(0.0, 2 * std::numbers::pi));
  phase_.store(oscillator_.phase(), std::memory_order_relaxed);
}

void OscillatorTask::on_tick() {
  oscillator_.step(seconds(now()));
  counters_.steps.bump();
  const double phase = oscillator_.phase();
  phase_.store(phase, std::memory_order_relaxed);
  const auto out = static_cast<float>(oscillator_.output());
  send(kJointTargetPort, {out});
  send(kPhasePort, {static_cast<float>(o_.id), static_cast<float>(phase)});
  if (probing()) probe("oscillator", {static_cast<float>(phase), out, static_cast<float>(oscillator_.coupled())});
}

void OscillatorTask::on_message(const os::Message& m) {
  if (m.payload.blob || m.port != kPhasePort) return ignore("a message that is not [id, phase] on port 1");
  const auto v = m.numbers();
  if (v.size() != 2 || !std::isfinite(v[0]) || !std::isfinite(v[1]) || v[0] != std::round(v[0]))
    return ignore("a phase message that is not [integer id, finite phase]");
  if (!oscillator_.hear(static_cast<std::int32_t>(v[0]), v[1], seconds(m.time))) {
    counters_.foreign.bump();
    return;
  }
  counters_.heard.bump();
}

void OscillatorTask::ignore(const char* why) {
  counters_.ignored.bump();
  if (warning_.note(now()))
    log(os::LogLevel::kWarn,
        std::string("ignored ") + why + " (" + std::to_string(warning_.count()) + " since the last warning)");
}

kernel::Status OscillatorTask::on_parameter_changed(std::string_view /*name*/) {
  oscillator_.set_params(params_of(o_));
  return {};
}

OscillatorStats OscillatorTask::stats() const {
  return OscillatorStats{.steps = counters_.steps.load(),
                         .heard = counters_.heard.load(),
                         .foreign = counters_.foreign.load(),
                         .ignored = counters_.ignored.load()};
}

}  // namespace symb::control::cpg
