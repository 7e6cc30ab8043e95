#include "symb/control/subsumption/subsumption_layers.hpp"

#include <algorithm>
#include <cmath>
#include <variant>

#include "symb/os/message.hpp"
#include "symb/os/node.hpp"

namespace symb::control {

namespace {

float finite_clamped(double v, double limit) {
  if (!std::isfinite(v)) return 0.0f;
  return static_cast<float>(std::clamp(v, -limit, limit));
}

}  // namespace

void SubsumptionLayer::act(double left, double right) {
  const float l = finite_clamped(left, options_.speed_limit);
  const float r = finite_clamped(right, options_.speed_limit);
  active_.store(true, std::memory_order_relaxed);
  commands_.fetch_add(1, std::memory_order_relaxed);
  if (!options_.inhibit.empty() && options_.inhibit_for.count() > 0) {
    // Looked up at each step: the inhibited layer may have been replaced meanwhile.
    if (auto target = node().find(options_.inhibit); target && *target != id())
      (void)node().inhibit(*target, os::TaskId{}, options_.inhibit_for);
  }
  send(kLayerOutputPort, {l, r});
  probe("active", {1.0f});
  probe("output", {l, r});
}

void SubsumptionLayer::rest() {
  active_.store(false, std::memory_order_relaxed);
  probe("active", {0.0f});
  probe("output", {0.0f, 0.0f});
}

// --- wander ------------------------------------------------------------------------------------------

void WanderLayer::on_tick() {
  const kernel::Time t = now();
  if (!next_change_ || t >= *next_change_) {
    turn_ = random().uniform(-o_.turn_max, o_.turn_max);
    const double mean = std::chrono::duration<double>(o_.change_every).count();
    const double wait = random().uniform(0.5 * mean, 1.5 * mean);
    next_change_ = t + std::chrono::duration_cast<kernel::Duration>(std::chrono::duration<double>(wait));
  }
  act(o_.speed - turn_, o_.speed + turn_);
}

kernel::Status WanderLayer::on_parameter_changed(std::string_view name) {
  if (name == "turn_max") turn_ = std::clamp(turn_, -o_.turn_max, o_.turn_max);
  if (name == "change_every") next_change_.reset();
  return {};
}

// --- avoid -------------------------------------------------------------------------------------------

void AvoidLayer::on_message(const os::Message& m) {
  if (m.payload.blob || m.port != kLayerInputPort) return;
  const auto v = m.numbers();
  if (v.size() < 5 || !os::all_finite(v)) return;
  const kernel::Time t = now();
  const bool sees = std::any_of(v.begin(), v.begin() + 5, [&](float x) { return x > o_.threshold; });
  if (sees) {
    last_seen_ = t;
    if (!episode_) {
      // Turn away from the side that sees more; the centre alone keeps the last direction.
      const double left = 2.0 * v[0] + v[1];
      const double right = 2.0 * v[4] + v[3];
      if (left > right) direction_ = -1;
      if (right > left) direction_ = 1;
      episode_ = true;
    }
  } else if (episode_ && t - last_seen_ >= o_.hold) {
    episode_ = false;
  }
  if (!episode_) {
    rest();
    return;
  }
  act(o_.forward - direction_ * o_.turn, o_.forward + direction_ * o_.turn);
}

// --- stop in zone ------------------------------------------------------------------------------------

void StopInZoneLayer::on_message(const os::Message& m) {
  if (m.payload.blob || m.port != kLayerInputPort) return;
  const auto v = m.numbers();
  if (v.size() != 2 || !os::all_finite(v)) return;
  const auto inside = [&](float x) { return x >= o_.zone_min && x <= o_.zone_max; };
  const kernel::Time t = now();
  if (!(inside(v[0]) && inside(v[1]))) {
    entered_.reset();
  } else if (!entered_) {
    entered_ = t;
  }
  const bool in_zone = entered_ && t - *entered_ >= o_.after;
  if (in_zone && o_.latch) latched_ = true;
  if (in_zone || latched_) {
    act(0, 0);
  } else {
    rest();
  }
}

kernel::Status StopInZoneLayer::on_parameter_changed(std::string_view name) {
  if (name == "latch" && !o_.latch) latched_ = false;
  return {};
}

}  // namespace symb::control
