#include "symb/evo/genome/real_genome.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <string>

#include "symb/kernel/source_text.hpp"

namespace symb::evo {

namespace {

double clamp_sigma(const RealGenome& g, double s) {
  // std::clamp would be undefined if a caller broke sigma_min <= sigma_max; check() reports that.
  if (s > g.sigma_max) s = g.sigma_max;
  if (s < g.sigma_min) s = g.sigma_min;
  return s;
}

bool compatible(const RealGenome& a, const RealGenome& b) {
  return a.values.size() == b.values.size() && a.lo == b.lo && a.hi == b.hi && a.lo < a.hi;
}

}  // namespace

kernel::Status check(const RealGenome& g) {
  if (!std::isfinite(g.lo) || !std::isfinite(g.hi) || !(g.lo < g.hi))
    return kernel::Error{"bounds [" + kernel::shortest_text<double>(g.lo) + ", " + kernel::shortest_text<double>(g.hi) +
                         "]: need finite lo < hi"};
  for (std::size_t i = 0; i < g.values.size(); ++i) {
    const double v = g.values[i];
    if (!std::isfinite(v)) return kernel::Error{"value " + std::to_string(i) + ": not finite"};
    if (v < g.lo || v > g.hi)
      return kernel::Error{"value " + std::to_string(i) + ": " + kernel::shortest_text<double>(v) + " outside [" +
                           kernel::shortest_text<double>(g.lo) + ", " + kernel::shortest_text<double>(g.hi) + "]"};
  }
  if (!std::isfinite(g.sigma_min) || !std::isfinite(g.sigma_max) || !std::isfinite(g.sigma) || !(g.sigma_min > 0) ||
      !(g.sigma_min <= g.sigma) || !(g.sigma <= g.sigma_max))
    return kernel::Error{"sigma " + kernel::shortest_text<double>(g.sigma) + " min " +
                         kernel::shortest_text<double>(g.sigma_min) + " max " +
                         kernel::shortest_text<double>(g.sigma_max) + ": need 0 < min <= sigma <= max, all finite"};
  return {};
}

RealGenome random_real_genome(std::size_t n, kernel::RandomStream& random, double lo, double hi, double sigma) {
  RealGenome g;
  g.lo = lo;
  g.hi = hi;
  g.sigma = sigma;
  g.values.reserve(n);
  for (std::size_t i = 0; i < n; ++i) g.values.push_back(std::min(random.uniform(lo, hi), hi));
  return g;
}

double reflect(double v, double lo, double hi) {
  if (!(lo < hi)) return lo;
  if (!std::isfinite(v)) return lo + (hi - lo) / 2;  // the contract says finite; stay defined anyway
  if (v >= lo && v <= hi) return v;
  // Bouncing between two walls is periodic with period 2w: fold v - lo into [0, 2w), then the
  // second half of the period runs back down. fmod is exact, and folding v and lo separately keeps
  // v - lo from overflowing for values near the double range.
  const double w = hi - lo;
  const double period = 2 * w;
  if (!std::isfinite(period)) return std::clamp(v, lo, hi);  // bounds near the double range
  double t = std::fmod(std::fmod(v, period) - std::fmod(lo, period), period);
  if (t < 0) t += period;
  if (t > w) t = period - t;
  return std::clamp(lo + t, lo, hi);  // rounding of lo + t must not leave the interval
}

void mutate_gaussian(RealGenome& g, kernel::RandomStream& random) {
  for (double& v : g.values) v = reflect(v + g.sigma * random.normal(), g.lo, g.hi);
}

void on_success(RealGenome& g) { g.sigma = g.sigma_min; }

void on_failure(RealGenome& g) { g.sigma = clamp_sigma(g, 2 * g.sigma); }

void mutate_sigma_medea(RealGenome& g, kernel::RandomStream& random, double p, double factor) {
  if (!(random.uniform() < p)) return;
  const bool up = random.uniform() < 0.5;
  g.sigma = clamp_sigma(g, g.sigma * (up ? 1 + factor : 1 - factor));
}

void mutate_sigma_lognormal(RealGenome& g, kernel::RandomStream& random) {
  const double n = static_cast<double>(std::max<std::size_t>(g.values.size(), 1));
  const double tau = 1 / std::sqrt(n);
  g.sigma = clamp_sigma(g, g.sigma * std::exp(tau * random.normal()));
}

RealGenome crossover_uniform(const RealGenome& a, const RealGenome& b, kernel::RandomStream& random) {
  RealGenome child = a;
  if (!compatible(a, b)) return child;
  for (std::size_t i = 0; i < child.values.size(); ++i)
    if (random.uniform() < 0.5) child.values[i] = b.values[i];
  child.sigma = clamp_sigma(child, (a.sigma + b.sigma) / 2);
  return child;
}

RealGenome crossover_arithmetic(const RealGenome& a, const RealGenome& b, kernel::RandomStream& random) {
  RealGenome child = a;
  if (!compatible(a, b)) return child;
  const double w = random.uniform();
  for (std::size_t i = 0; i < child.values.size(); ++i)
    child.values[i] = std::clamp(w * a.values[i] + (1 - w) * b.values[i], a.lo, a.hi);
  child.sigma = clamp_sigma(child, (a.sigma + b.sigma) / 2);
  return child;
}

std::string weights_text(const RealGenome& g) {
  constexpr double kFloatMax = std::numeric_limits<float>::max();
  // The network holds floats: each value is written as the float it becomes, in the shortest form
  // that reads back to that float.
  std::string out;
  char buf[32];
  for (std::size_t i = 0; i < g.values.size(); ++i) {
    if (i) out += ' ';
    // A double beyond the float range has no float to become (the cast would be undefined): it
    // is written as the largest float of its sign.
    const double v = g.values[i] > kFloatMax ? kFloatMax : g.values[i] < -kFloatMax ? -kFloatMax : g.values[i];
    auto [end, ec] = std::to_chars(buf, buf + sizeof buf, static_cast<float>(v));
    (void)ec;
    out.append(buf, end);
  }
  return out;
}

}  // namespace symb::evo
