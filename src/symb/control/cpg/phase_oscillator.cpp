#include "symb/control/cpg/phase_oscillator.hpp"

#include <algorithm>
#include <cmath>

namespace symb::control::cpg {

namespace {
constexpr double kTwoPi = 2 * std::numbers::pi;
}

double PhaseOscillator::wrap(double angle) {
  double a = std::fmod(angle, kTwoPi);
  if (a < 0) a += kTwoPi;
  return a >= kTwoPi ? 0.0 : a;
}

bool PhaseOscillator::hear(std::int32_t id, double phase, double sent) {
  if (!std::isfinite(phase) || !std::isfinite(sent)) return false;
  const std::int64_t d = static_cast<std::int64_t>(id) - p_.id;
  if (d != -1 && d != 1) return false;
  heard_[d < 0 ? 0 : 1] = Heard{wrap(phase), sent};
  return true;
}

double PhaseOscillator::rate(double t) const {
  double r = kTwoPi * p_.frequency;
  for (std::size_t k = 0; k < heard_.size(); ++k) {
    if (!heard_[k] || t - heard_[k]->sent > p_.neighbour_timeout) continue;
    const double theirs = heard_[k]->phase + kTwoPi * p_.frequency * (t - heard_[k]->sent);
    const double offset = k == 0 ? p_.lag : -p_.lag;  // (i - j) * lag
    r += p_.coupling * std::sin(theirs - phase_ - offset);
  }
  return r;
}

void PhaseOscillator::step(double now) {
  if (!time_ || now <= *time_) {
    if (!time_) time_ = now;
    return;
  }
  // Equal steps counted up front: a loop on `t < now` could take steps too small to move t.
  const double start = *time_;
  const double span = now - start;
  const auto n = static_cast<std::int64_t>(std::ceil(span / kMaxOscillatorStep));
  const double dt = span / static_cast<double>(n);
  for (std::int64_t k = 0; k < n; ++k) phase_ = wrap(phase_ + dt * rate(start + static_cast<double>(k) * dt));
  time_ = now;
  coupled_ = 0;
  for (const auto& h : heard_)
    if (h && now - h->sent <= p_.neighbour_timeout) ++coupled_;
}

double PhaseOscillator::output() const { return p_.offset + p_.amplitude * std::sin(phase_); }

}  // namespace symb::control::cpg
