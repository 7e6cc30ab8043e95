#include "symb/evo/arbiter/arbiter_task.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

#include "symb/robot/ports.hpp"

namespace symb::evo {

namespace {

double seconds(kernel::Duration d) { return std::chrono::duration<double>(d).count(); }

}  // namespace

double danger(std::span<const float> ir, const ArbiterOptions& options) {
  double d = 0;
  for (std::size_t i = 0; i < std::min<std::size_t>(5, ir.size()); ++i)
    d = std::max(d, std::clamp(static_cast<double>(ir[i]) / options.ir_max, 0.0, 1.0));
  return d;
}

double predicted_step_fitness(std::span<const float> ir, double left, double right, const ArbiterOptions& options) {
  if (ir.size() < 5 || !std::isfinite(left) || !std::isfinite(right)) return -1;
  const auto proximity = [&](std::size_t i) {
    return std::clamp(static_cast<double>(ir[i]) / options.ir_max, 0.0, 1.0);
  };
  const double l = std::clamp(left / options.speed_max, -1.0, 1.0);
  const double r = std::clamp(right / options.speed_max, -1.0, 1.0);
  const double d = danger(ir, options);
  const double forward = std::max(0.0, (l + r) / 2);
  const double speed_term = forward * (1 - std::sqrt(std::abs(l - r) / 2));
  // Positive turn: clockwise (left wheel faster), away from an obstacle on the left.
  const double turn = (l - r) / 2;
  // A wall mostly ahead may be left either way; one mostly on a side must be turned away from.
  const double on_left = proximity(0) + proximity(1), on_right = proximity(3) + proximity(4);
  const double away = proximity(2) >= std::max(on_left, on_right) || std::abs(on_left - on_right) < 0.05
                          ? std::abs(turn)
                          : (on_left > on_right ? turn : -turn);
  return std::clamp((1 - d) * speed_term + d * (away - forward), -1.0, 1.0);
}

ArbiterTask::ArbiterTask(ArbiterOptions options) : options_(options) { bind_parameters(options_); }

ArbiterStats ArbiterTask::stats() const {
  std::lock_guard lock(mu_);
  return stats_;
}

ArbiterVariant* ArbiterTask::variant(os::TaskId id) {
  for (ArbiterVariant& v : stats_.variants)
    if (v.source == id) return &v;
  return nullptr;
}

void ArbiterTask::switch_to(std::optional<os::TaskId> id) {
  if (stats_.active == id) return;
  if (stats_.active && id) ++stats_.switches;
  stats_.active = id;
  last_switch_ = now();
}

void ArbiterTask::on_message(const os::Message& m) {
  const auto values = m.numbers();
  if (m.port != 0 || m.payload.blob || values.size() < 2 || (values.size() > 2 && !os::all_finite(values))) {
    std::lock_guard lock(mu_);
    ++stats_.ignored;
    return;
  }
  if (values.size() == 2)
    on_command(m.source, values[0], values[1]);
  else
    on_reading(values);
}

void ArbiterTask::drop_stale() {
  const kernel::Time t = now();
  const auto before = stats_.variants.size();
  std::erase_if(stats_.variants, [&](const ArbiterVariant& v) { return t - v.last > options_.stale; });
  stats_.dropped += before - stats_.variants.size();
  if (stats_.active && !variant(*stats_.active)) {
    // The driver went quiet: hand the wheels to the best one left, without waiting for the dwell.
    const auto best =
        std::max_element(stats_.variants.begin(), stats_.variants.end(),
                         [](const ArbiterVariant& a, const ArbiterVariant& b) { return a.average < b.average; });
    stats_.active = std::nullopt;
    if (best != stats_.variants.end()) {
      stats_.active = best->source;
      ++stats_.switches;
      last_switch_ = t;
    }
  }
}

void ArbiterTask::on_reading(std::span<const float> ir) {
  ir_.assign(ir.begin(), ir.end());
  std::vector<float> scores;
  float active_index = -1;
  {
    std::lock_guard lock(mu_);
    drop_stale();
    for (std::size_t i = 0; i < stats_.variants.size(); ++i) {
      scores.push_back(static_cast<float>(stats_.variants[i].average));
      if (stats_.active == stats_.variants[i].source) active_index = static_cast<float>(i);
    }
  }
  if (probing()) {
    probe("arbiter/active", {active_index});
    probe("arbiter/scores", scores);
  }
}

void ArbiterTask::on_command(os::TaskId source, float left, float right) {
  const kernel::Time t = now();
  bool forward = false;
  {
    std::lock_guard lock(mu_);
    ArbiterVariant* v = variant(source);
    if (!v) {
      ArbiterVariant fresh;
      fresh.source = source;
      fresh.last = t;
      stats_.variants.push_back(fresh);
      v = &stats_.variants.back();
    }
    const double dt = seconds(t - v->last);
    v->last = t;
    if (ir_.size() >= 5) {
      const double score = predicted_step_fitness(ir_, left, right, options_);
      // Weighted by the proximity: in open space every sane variant drives straight on and scores
      // alike, near a wall they differ, so those moments must not drown in the open ones.
      const double weight = options_.open_weight + danger(ir_, options_);
      // An exponential window in time; the first samples average plainly so the start counts.
      const double alpha = v->samples == 0 ? 1.0
                                           : std::max(1.0 / static_cast<double>(v->samples + 1),
                                                      1 - std::exp(-std::max(dt, 1e-3) / seconds(options_.window)));
      v->weighted_sum += alpha * (weight * score - v->weighted_sum);
      v->weight_sum += alpha * (weight - v->weight_sum);
      v->average = v->weight_sum > 0 ? v->weighted_sum / v->weight_sum : 0.0;
      ++v->samples;
    }
    if (!stats_.active) {
      switch_to(source);
    } else if (*stats_.active != source && v->samples >= options_.min_samples && t - last_switch_ >= options_.dwell) {
      const ArbiterVariant* driver = variant(*stats_.active);
      if (!driver || v->average > driver->average + options_.margin) switch_to(source);
    }
    forward = stats_.active == source && std::isfinite(left) && std::isfinite(right);
    if (forward) ++stats_.forwarded;
  }
  if (forward) {
    const auto limit = static_cast<float>(options_.speed_max);
    send(0, {std::clamp(left, -limit, limit), std::clamp(right, -limit, limit)});
  }
}

os::TaskType arbiter_task_type() {
  using P = ArbiterOptions;
  os::ParamTable<P> p;
  p.add("ir_max", &P::ir_max).range(1.0, 1e6).doc("an IR value that means touching");
  p.add("speed_max", &P::speed_max).range(1e-3, 1e6).doc("full wheel speed; commands are clamped to it");
  p.add("window", &P::window).range(0.001, 3600.0).doc("time constant of each variant's average score").live();
  p.add("margin", &P::margin).range(0.0, 2.0).doc("how much a challenger must beat the driver by").live();
  p.add("dwell", &P::dwell).range(0.0, 3600.0).doc("shortest time between two switches").live();
  p.add("stale", &P::stale).range(0.001, 3600.0).doc("a variant silent this long is forgotten").live();
  p.add("open_weight", &P::open_weight)
      .range(0.0, 100.0)
      .doc("weight of a step in open space in the average (a step touching a wall weighs open_weight + 1)")
      .live();
  p.add("min_samples", &P::min_samples).range(1.0, 1e6).doc("scored commands before a variant may challenge");
  auto t = os::declare_task_type(
      "arbiter",
      "runs several controller variants side by side: IR readings and each variant's [left, right] in on port 0, "
      "the best-scoring variant's commands out on port 0 (docs/evolution.md, multiple controllers)",
      std::move(p), [](const P& o) { return std::make_unique<ArbiterTask>(o); });
  t.defaults.priority = 1;
  t.defaults.queue_capacity = 32;
  t.outputs = {{0, "wheels", robot::layout::kWheelCommand}};
  return t;
}

kernel::Status register_arbiter_task_type(os::TaskTypeRegistry& registry) { return registry.add(arbiter_task_type()); }

}  // namespace symb::evo
