// snn_bench: Izhikevich spiking networks (symb/control/snn/spiking_network.hpp) of 10^3, 10^4 and
// 10^5 neurons with 100 synapses each, stepped in 1 ms steps, against a NAIVE reference measured
// in the same run: an array of structs of double v, u, a, b, c, d, a std::vector<Synapse> per
// neuron and the pending pulses in a std::multimap keyed by their due step.
//
// The networks: 80 % RS (excitatory, weights 2 U[0, 1)), 20 % FS (inhibitory, -3 U[0, 1)),
// random targets, delays 1..20 ms, and per step a Gaussian input current of sigma 6.5 to every
// neuron (read from a precomputed table at a moving offset, the same for both sides, so drawing
// random numbers does not dominate the timing). Tuned to about 10 Hz mean rate (printed).
// Counters: neuron updates/s, synaptic events/s (spikes x 100), the real-time factor (biological
// ms simulated per wall ms) and the mean rate. Target: 10^4 neurons at >= 10x real time.
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "symb/control/snn/spiking_network.hpp"
#include "symb/kernel/random_stream.hpp"

#include "bench_report.hpp"

namespace {

using namespace symb;
using namespace symb::control::snn;

constexpr std::size_t kSynapsesPerNeuron = 100;
constexpr double kExcitatoryWeight = 2.0, kInhibitoryWeight = 3.0, kNoiseSigma = 6.5;
constexpr std::size_t kNoiseStride = 997;  // distinct offsets into the noise table
constexpr int kWarmupMs = 200;             // past the synchronous onset before timing
constexpr double kTargetRealTime = 10.0;
constexpr std::int64_t kTargetSize = 10000;

NetworkSpec make_spec(std::size_t n) {
  kernel::RandomStream r(42, n);
  NetworkSpec spec;
  const std::size_t excitatory = n * 4 / 5;
  spec.neurons.reserve(n);
  for (std::size_t i = 0; i < n; ++i)
    spec.neurons.push_back(params_of(i < excitatory ? NeuronClass::kRS : NeuronClass::kFS));
  spec.synapses.reserve(n * kSynapsesPerNeuron);
  for (std::size_t j = 0; j < n; ++j)
    for (std::size_t k = 0; k < kSynapsesPerNeuron; ++k) {
      const double w = j < excitatory ? kExcitatoryWeight * r.uniform() : -kInhibitoryWeight * r.uniform();
      spec.synapses.push_back({static_cast<std::uint32_t>(j), static_cast<std::uint32_t>(r.below(n)),
                               static_cast<float>(w), static_cast<std::uint32_t>(1 + r.below(20))});
    }
  return spec;
}

std::vector<float> make_noise(std::size_t n) {
  kernel::RandomStream r(7, n);
  std::vector<float> noise(n + kNoiseStride);
  for (float& x : noise) x = static_cast<float>(r.normal(0, kNoiseSigma));
  return noise;
}

std::size_t noise_offset(std::uint64_t t) { return static_cast<std::size_t>((t * 7919) % kNoiseStride); }

// The straightforward per-neuron implementation, published scheme, in double.
class Naive {
 public:
  explicit Naive(const NetworkSpec& spec) : synapses_(spec.neurons.size()), current_(spec.neurons.size()) {
    for (const NeuronParams& p : spec.neurons) neurons_.push_back({-65.0, p.b * -65.0, p.a, p.b, p.c, p.d});
    for (const Synapse& s : spec.synapses) synapses_[s.source].push_back(s);
  }
  std::size_t size() const { return neurons_.size(); }
  std::vector<double>& input() { return current_; }
  // One 1 ms step; the number of neurons that fired.
  std::size_t step() {
    std::size_t fired = 0;
    for (std::size_t i = 0; i < neurons_.size(); ++i) {
      Neuron& x = neurons_[i];
      if (x.v < 30.0) continue;
      ++fired;
      x.v = x.c;
      x.u += x.d;
      for (const Synapse& s : synapses_[i]) pending_.emplace(time_ + s.delay, Pulse{s.target, s.weight});
    }
    const auto due = pending_.equal_range(time_);
    for (auto p = due.first; p != due.second; ++p) current_[p->second.target] += p->second.weight;
    pending_.erase(due.first, due.second);
    for (std::size_t i = 0; i < neurons_.size(); ++i) {
      Neuron& x = neurons_[i];
      const double current = current_[i];
      x.v += 0.5 * (0.04 * x.v * x.v + 5 * x.v + 140 - x.u + current);
      x.v += 0.5 * (0.04 * x.v * x.v + 5 * x.v + 140 - x.u + current);
      x.u += x.a * (x.b * x.v - x.u);
      current_[i] = 0;
    }
    ++time_;
    return fired;
  }

 private:
  struct Neuron {
    double v, u, a, b, c, d;
  };
  struct Pulse {
    std::uint32_t target;
    float weight;
  };
  std::vector<Neuron> neurons_;
  std::vector<std::vector<Synapse>> synapses_;
  std::multimap<std::uint64_t, Pulse> pending_;
  std::vector<double> current_;
  std::uint64_t time_ = 0;
};

// Both sides keep their state across repetitions (built once, warmed up, then in steady state).
struct Fixture {
  std::vector<float> noise;
  std::unique_ptr<SpikingNetwork> framework;
  std::unique_ptr<Naive> naive;
  std::uint64_t framework_t = 0, naive_t = 0;
};

std::map<std::size_t, Fixture>& fixtures() {
  static std::map<std::size_t, Fixture> f;
  return f;
}

Fixture& fixture(std::size_t n) {
  Fixture& f = fixtures()[n];
  if (f.noise.empty()) f.noise = make_noise(n);
  return f;
}

std::size_t step_framework(Fixture& f) {
  SpikingNetwork& net = *f.framework;
  const float* noise = f.noise.data() + noise_offset(f.framework_t++);
  const std::span<float> in = net.input();
  for (std::size_t i = 0; i < in.size(); ++i) in[i] += noise[i];
  return net.step().size();
}

std::size_t step_naive(Fixture& f) {
  const float* noise = f.noise.data() + noise_offset(f.naive_t++);
  std::vector<double>& in = f.naive->input();
  for (std::size_t i = 0; i < in.size(); ++i) in[i] += noise[i];
  return f.naive->step();
}

void report(benchmark::State& state, std::size_t n, std::size_t spikes) {
  const auto steps = static_cast<double>(state.iterations());
  state.counters["neuron_updates_per_s"] =
      benchmark::Counter(static_cast<double>(n) * steps, benchmark::Counter::kIsRate);
  state.counters["syn_events_per_s"] =
      benchmark::Counter(static_cast<double>(spikes * kSynapsesPerNeuron), benchmark::Counter::kIsRate);
  // Biological seconds per second: the real-time factor (bio ms per wall ms).
  state.counters["real_time_factor"] = benchmark::Counter(steps / 1000.0, benchmark::Counter::kIsRate);
  state.counters["rate_hz"] = static_cast<double>(spikes) / static_cast<double>(n) / (steps / 1000.0);
}

void BM_Framework(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  Fixture& f = fixture(n);
  if (!f.framework) {
    auto net = SpikingNetwork::create(make_spec(n));
    if (!net) {
      state.SkipWithError(net.error().c_str());
      return;
    }
    f.framework = std::make_unique<SpikingNetwork>(std::move(net.value()));
    for (int t = 0; t < kWarmupMs; ++t) step_framework(f);
  }
  std::size_t spikes = 0;
  for (auto _ : state) spikes += step_framework(f);
  report(state, n, spikes);
}

void BM_Naive(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  Fixture& f = fixture(n);
  if (!f.naive) {
    f.naive = std::make_unique<Naive>(make_spec(n));
    for (int t = 0; t < kWarmupMs; ++t) step_naive(f);
  }
  std::size_t spikes = 0;
  for (auto _ : state) spikes += step_naive(f);
  report(state, n, spikes);
}

constexpr int kRepetitions = 3;
BENCHMARK(BM_Framework)->Arg(1000)->Arg(10000)->Arg(100000)->Repetitions(kRepetitions)->MinTime(0.3);
BENCHMARK(BM_Naive)->Arg(1000)->Arg(10000)->Arg(100000)->Repetitions(kRepetitions)->MinTime(0.3);

}  // namespace

int main(int argc, char** argv) {
  symb::bench::CollectingReporter reporter(false);
  if (!symb::bench::run_interleaved(argc, argv, reporter)) return 1;

  std::printf("\nIzhikevich networks, 100 synapses per neuron (median of repetitions)\n");
  std::printf("%-9s %-9s %14s %14s %10s %8s\n", "neurons", "side", "updates/s", "syn events/s", "x realtime",
              "rate Hz");
  double target_rtf = 0;
  for (std::int64_t n : {1000, 10000, 100000}) {
    const std::string a = "/" + std::to_string(n);
    double rtf[2] = {0, 0};
    int side = 0;
    for (const char* name : {"BM_Framework", "BM_Naive"}) {
      const std::string b = name + a;
      rtf[side] = reporter.median(b, "real_time_factor");
      std::printf("%-9lld %-9s %14.3g %14.3g %10.2f %8.2f\n", static_cast<long long>(n),
                  side == 0 ? "framework" : "naive", reporter.median(b, "neuron_updates_per_s"),
                  reporter.median(b, "syn_events_per_s"), rtf[side], reporter.median(b, "rate_hz"));
      ++side;
    }
    std::printf("%-9lld framework/naive: %.1fx\n", static_cast<long long>(n), rtf[1] > 0 ? rtf[0] / rtf[1] : 0.0);
    if (n == kTargetSize) target_rtf = rtf[0];
  }
  for (const auto& e : reporter.errors()) std::printf("ERROR %s\n", e.c_str());
  const bool met = target_rtf >= kTargetRealTime && reporter.errors().empty();
  std::printf("snn: 10^4 neurons x 100 synapses at %.1fx real time on one core, target >= %.0fx: %s\n", target_rtf,
              kTargetRealTime, met ? "MET" : "NOT MET");
  return 0;
}
