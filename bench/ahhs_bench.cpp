// ahhs_bench: AHHS compartment-hormone updates per second (one update = one hormone of one
// compartment through one whole step: emission, decay, rules, clamping, diffusion) for
//   (a) 3 compartments x 8 hormones x 20 rules (the tuned experiments' size), and
//   (b) a 1,000-compartment organism graph (a 40 x 25 grid of neighbours), 8 hormones, 20 rules,
// for the model (symb/control/ahhs/model.hpp) and, in the same run, for a NAIVE reference: a
// straightforward transcription of the authors' 2009 loops (per compartment, per hormone, scan
// every rule; diffusion scans every compartment for neighbours). Both must agree on the levels
// (checked before timing). Target: the model >= 5x the naive one for the large graph.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "symb/control/ahhs/model.hpp"
#include "symb/kernel/random_stream.hpp"

#include "bench_report.hpp"

namespace {

using namespace symb;
using namespace symb::control::ahhs;

constexpr int kSmall = 0, kLarge = 1;
constexpr double kTargetRatio = 5.0;
constexpr std::size_t kHormones = 8, kRules = 20, kSensors = 4, kActuators = 2;

Network make_network(int which) {
  kernel::RandomStream r(42, static_cast<std::uint64_t>(which));
  Network n;
  if (which == kSmall) {
    n.compartments = 3;
    n.links = {{0, 1}, {1, 2}, {0, 2}};
  } else {
    constexpr std::uint32_t w = 40, h = 25;
    n.compartments = w * h;
    for (std::uint32_t y = 0; y < h; ++y)
      for (std::uint32_t x = 0; x < w; ++x) {
        if (x + 1 < w) n.links.push_back({y * w + x, y * w + x + 1});
        if (y + 1 < h) n.links.push_back({y * w + x, (y + 1) * w + x});
      }
  }
  // The authors' initialisation ranges; diffusion within 1 / (largest degree 4).
  for (std::size_t k = 0; k < kHormones; ++k)
    n.hormones.push_back({"h" + std::to_string(k), static_cast<float>(r.uniform(0, 0.1)),
                          static_cast<float>(r.uniform(0, 0.1)), static_cast<float>(r.uniform(0, 0.1)), 0, 1, 0});
  for (std::uint32_t s = 0; s < kSensors; ++s)
    n.sensors.push_back({s, static_cast<std::uint32_t>(r.below(n.compartments))});
  for (std::uint32_t a = 0; a < kActuators; ++a)
    n.actuators.push_back({a, static_cast<std::uint32_t>(r.below(n.compartments))});
  for (std::size_t k = 0; k < kRules; ++k) {
    Rule x;
    // Mostly hormone rules (they run in every compartment), a few sensor and actuator rules.
    const std::uint64_t kind = r.below(10);
    x.kind = kind < 2   ? RuleKind::kSensor
             : kind < 4 ? RuleKind::kActuator
             : kind < 7 ? RuleKind::kHormone
                        : RuleKind::kNonlinear;
    x.source = static_cast<std::uint32_t>(x.kind == RuleKind::kSensor ? r.below(kSensors) : r.below(kHormones));
    x.target = static_cast<std::uint32_t>(x.kind == RuleKind::kActuator ? r.below(kActuators) : r.below(kHormones));
    x.centre = static_cast<float>(r.uniform(0, 1));
    x.width = static_cast<float>(r.uniform(0.5, 1));
    x.fixed = static_cast<float>(r.uniform(-0.2, 0.2));
    x.dependent = static_cast<float>(r.uniform(-2, 2));
    n.rules.push_back(x);
  }
  return n;
}

// The naive reference: the 2009 code's loop structure, with the equations of the model (linear
// hormone rules regulate their target, diffusion between listed neighbours only).
class Naive {
 public:
  explicit Naive(const Network& n) : n_(n), nc_(n.compartments), nh_(n.hormones.size()) {
    h_.assign(nc_ * nh_, 0.0f);
    for (std::size_t c = 0; c < nc_; ++c)
      for (std::size_t h = 0; h < nh_; ++h) h_[c * nh_ + h] = n.hormones[h].start;
    next_ = h_;
    adjacent_.assign(nc_ * nc_, false);
    for (auto [a, b] : n.links) adjacent_[a * nc_ + b] = adjacent_[b * nc_ + a] = true;
    a_.assign(n.actuators.size(), 0.0f);
  }

  void step(const std::vector<float>& sensors) {
    std::fill(a_.begin(), a_.end(), 0.0f);
    for (std::size_t c = 0; c < nc_; ++c)
      for (std::size_t h = 0; h < nh_; ++h) {
        const float x = h_[c * nh_ + h];
        float d = n_.hormones[h].base - n_.hormones[h].decay * x;
        for (const Rule& r : n_.rules) {
          switch (r.kind) {
            case RuleKind::kSensor: {
              if (r.target != h) break;
              bool here = false;
              for (const Placement& p : n_.sensors) here = here || (p.index == r.source && p.compartment == c);
              if (!here) break;
              const float s = sensors[r.source];
              const float t = trigger(s, r.centre, r.width);
              if (t != 0.0f) d += t * (r.dependent * s + r.fixed);
              break;
            }
            case RuleKind::kHormone:
            case RuleKind::kNonlinear: {
              if (r.target != h) break;
              if (r.compartment != kEveryCompartment && static_cast<std::size_t>(r.compartment) != c) break;
              const float src = h_[c * nh_ + r.source];
              const float t = trigger(src, r.centre, r.width);
              if (t == 0.0f) break;
              d += r.kind == RuleKind::kHormone ? t * (r.dependent * src + r.fixed)
                                                : t * (r.dependent * src * x + r.fixed);
              break;
            }
            case RuleKind::kActuator: {
              if (r.source != h) break;
              bool here = false;
              for (const Placement& p : n_.actuators) here = here || (p.index == r.target && p.compartment == c);
              if (!here) break;
              const float t = trigger(x, r.centre, r.width);
              if (t != 0.0f) a_[r.target] += t * (r.dependent * x + r.fixed);
              break;
            }
          }
        }
        next_[c * nh_ + h] = std::clamp(x + d, n_.hormones[h].min, n_.hormones[h].max);
      }
    for (std::size_t c = 0; c < nc_; ++c)
      for (std::size_t h = 0; h < nh_; ++h) {
        const float x = next_[c * nh_ + h];
        float flow = 0;
        for (std::size_t m = 0; m < nc_; ++m)
          if (adjacent_[c * nc_ + m]) flow += x - next_[m * nh_ + h];
        h_[c * nh_ + h] = std::clamp(x - n_.hormones[h].diffusion * flow, n_.hormones[h].min, n_.hormones[h].max);
      }
    for (float& v : a_) v = std::clamp(v, -1.0f, 1.0f);
  }
  float level(std::size_t c, std::size_t h) const { return h_[c * nh_ + h]; }

 private:
  const Network& n_;
  std::size_t nc_, nh_;
  std::vector<float> h_, next_, a_;
  std::vector<bool> adjacent_;
};

std::vector<float> sensors_at(std::size_t t) {
  std::vector<float> s(kSensors);
  for (std::size_t k = 0; k < kSensors; ++k) s[k] = std::fmod(0.13f * static_cast<float>(t * (k + 1)), 1.0f);
  return s;
}

// Both implementations, 50 steps, levels compared: a benchmark of a wrong model is worthless.
bool agree(const Network& n, std::string& why) {
  auto m = Model::create(n);
  if (!m) {
    why = m.error();
    return false;
  }
  Naive naive(n);
  for (std::size_t t = 0; t < 50; ++t) {
    const auto s = sensors_at(t);
    m.value().step(s);
    naive.step(s);
  }
  for (std::size_t c = 0; c < n.compartments; ++c)
    for (std::size_t h = 0; h < n.hormones.size(); ++h)
      if (std::abs(m->levels(static_cast<std::uint32_t>(c))[h] - naive.level(c, h)) > 1e-4f) {
        why =
            "model and naive reference disagree at compartment " + std::to_string(c) + ", hormone " + std::to_string(h);
        return false;
      }
  return true;
}

void report(benchmark::State& state, const Network& n) {
  state.counters["updates_per_s"] = benchmark::Counter(
      static_cast<double>(n.compartments * n.hormones.size()) * static_cast<double>(state.iterations()),
      benchmark::Counter::kIsRate);
}

void BM_Model(benchmark::State& state) {
  const Network n = make_network(static_cast<int>(state.range(0)));
  std::string why;
  if (!agree(n, why)) {
    state.SkipWithError(why.c_str());
    return;
  }
  auto m = Model::create(n);
  std::size_t t = 0;
  const auto s0 = sensors_at(1), s1 = sensors_at(2);
  for (auto _ : state) {
    m.value().step(++t % 2 ? s0 : s1);
    benchmark::DoNotOptimize(m.value().levels(0).data());
    benchmark::ClobberMemory();
  }
  report(state, n);
}

void BM_Naive(benchmark::State& state) {
  const Network n = make_network(static_cast<int>(state.range(0)));
  Naive naive(n);
  std::size_t t = 0;
  const auto s0 = sensors_at(1), s1 = sensors_at(2);
  for (auto _ : state) {
    naive.step(++t % 2 ? s0 : s1);
    float x = naive.level(0, 0);
    benchmark::DoNotOptimize(x);
    benchmark::ClobberMemory();
  }
  report(state, n);
}

constexpr int kRepetitions = 5;
BENCHMARK(BM_Model)->Arg(kSmall)->Arg(kLarge)->Repetitions(kRepetitions)->MinTime(0.2);
BENCHMARK(BM_Naive)->Arg(kSmall)->Arg(kLarge)->Repetitions(kRepetitions)->MinTime(0.2);

}  // namespace

int main(int argc, char** argv) {
  symb::bench::CollectingReporter reporter(false);
  if (!symb::bench::run_interleaved(argc, argv, reporter)) return 1;

  std::printf("\nAHHS compartment-hormone updates per second (median of repetitions)\n");
  std::printf("%-36s %16s %16s %8s\n", "network", "model", "naive", "ratio");
  const char* names[] = {"(a) 3 compartments x 8 h x 20 rules", "(b) 1000 compartments (grid), 8 h"};
  double large_ratio = 0;
  for (int which : {kSmall, kLarge}) {
    const std::string a = "/" + std::to_string(which);
    const double model = reporter.median("BM_Model" + a, "updates_per_s");
    const double naive = reporter.median("BM_Naive" + a, "updates_per_s");
    const double ratio = naive > 0 ? model / naive : 0.0;
    if (which == kLarge) large_ratio = ratio;
    std::printf("%-36s %16.3g %16.3g %7.1fx\n", names[which], model, naive, ratio);
  }
  for (const auto& e : reporter.errors()) std::printf("ERROR %s\n", e.c_str());
  const bool met = large_ratio >= kTargetRatio && reporter.errors().empty();
  std::printf(
      "ahhs: model %.1fx the naive reference for the 1000-compartment graph, target >= %.0fx for the large "
      "graph: %s\n",
      large_ratio, kTargetRatio, met ? "MET" : "NOT MET");
  return 0;
}
