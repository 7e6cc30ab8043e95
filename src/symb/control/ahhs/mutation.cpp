#include "symb/control/ahhs/mutation.hpp"

#include <algorithm>
#include <cmath>

namespace symb::control::ahhs {

namespace {

float moved(float v, kernel::RandomStream& random, double step, double lo, double hi) {
  return static_cast<float>(std::clamp(static_cast<double>(v) + random.uniform(-step, step), lo, hi));
}

std::uint32_t max_degree(const Network& n) {
  std::vector<std::uint32_t> d(n.compartments, 0);
  for (auto [a, b] : n.links) {
    if (a < n.compartments) ++d[a];
    if (b < n.compartments) ++d[b];
  }
  return d.empty() ? 0 : *std::max_element(d.begin(), d.end());
}

}  // namespace

HormoneSlot mutate_hormone(Network& n, std::size_t hormone, kernel::RandomStream& random, double step) {
  Hormone& h = n.hormones[hormone];
  const auto slot = static_cast<HormoneSlot>(random.below(3));
  const std::uint32_t degree = max_degree(n);
  switch (slot) {
    case HormoneSlot::kBase: h.base = moved(h.base, random, step, -1.0, 1.0); break;
    case HormoneSlot::kDecay: h.decay = moved(h.decay, random, step, 0.0, 1.0); break;
    case HormoneSlot::kDiffusion:
      h.diffusion = moved(h.diffusion, random, step, 0.0, degree > 0 ? 1.0 / degree : 1.0);
      // 1 / degree rounded to float may land a hair above it.
      while (degree > 0 && static_cast<double>(h.diffusion) * degree > 1.0)
        h.diffusion = std::nextafter(h.diffusion, 0.0f);
      break;
  }
  return slot;
}

std::size_t mutate(Network& n, kernel::RandomStream& random, const MutationOptions& options) {
  std::size_t changed = 0;
  for (std::size_t h = 0; h < n.hormones.size(); ++h)
    if (random.uniform() < options.hormone_probability) {
      mutate_hormone(n, h, random, options.step);
      ++changed;
    }
  for (Rule& r : n.rules) {
    if (random.uniform() >= options.rule_probability) continue;
    switch (random.below(4)) {
      case 0: r.centre = moved(r.centre, random, options.step, -2.0, 2.0); break;
      case 1: r.width = moved(r.width, random, options.step, 1e-3, 2.0); break;
      case 2: r.fixed = moved(r.fixed, random, options.step, -2.0, 2.0); break;
      default: r.dependent = moved(r.dependent, random, options.step, -2.0, 2.0); break;
    }
    ++changed;
  }
  return changed;
}

}  // namespace symb::control::ahhs
