// Real-time factor of an organism through the whole framework (issue 16): a chain of N docked cube
// modules crawling like scenarios/caterpillar.yaml (an oscillator task on each module's node
// driving its hinge through the hinge device task, coupled to its neighbours' by remote hooks over
// the organism bus; the MujocoRunner publishing each module's IR and hinge state every control
// period; the wheels' watchdog holding them), beside raw MuJoCo stepping the same model (the same
// MJCF, the same docks) with the same control law called directly: the same PhaseOscillator per
// module, neighbours' phases handed over in memory, hinge targets set every 20 ms, from the same
// initial phases. Both run on one thread (the virtual-time executor for the framework) and are
// timed over the stepping only, in that thread's CPU time: the box is shared, and wall time would
// count the other processes' turns against whichever side they happened to interrupt. N = 5 (the
// target: >= 90 %), 20 and 50.
#include <time.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "symb/control/cpg/phase_oscillator.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/sim/mujoco/mujoco_world.hpp"
#include "symb/sim/mujoco/organism_session.hpp"
#include "symb/sim/scenario.hpp"

#include "bench_report.hpp"

namespace {

namespace fs = std::filesystem;

// This thread's CPU time, s.
double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}
using symb::sim::mujoco::MujocoWorld;

constexpr double kTarget5 = 0.90;
constexpr int kStepsPerTick = 10;  // 20 ms control period of 2 ms steps
constexpr double kFrequency = 1.0, kAmplitude = 0.6, kLag = -1.2, kCoupling = 4.0;

// Where oscillator i starts, the same on both sides (within the type's range of +-2 pi).
double initial_phase(int i) { return std::fmod(0.7 * i, 6.0); }

double simulated_seconds(int modules) { return modules <= 5 ? 40 : modules <= 20 ? 10 : 4; }

fs::path scenario_dir() { return fs::temp_directory_path() / ("symb_organism_bench_" + std::to_string(::getpid())); }

// scenarios/caterpillar.yaml for `modules` modules (the kind file by its absolute path).
fs::path write_scenario(int modules) {
  const fs::path dir = scenario_dir();
  fs::create_directories(dir);
  std::ostringstream y;
  y << "name: organism_" << modules << "\nseed: 1\nduration: " << simulated_seconds(modules)
    << "s\ncontrol_period: 20ms\nworld:\n  kind: mujoco\n  bus: {bandwidth: 1000000, latency: 1ms}\n  docked: [";
  for (int i = 0; i + 1 < modules; ++i) y << (i ? ", " : "") << "[m" << i << ".back, m" << i + 1 << ".front]";
  y << "]\nrobots:\n";
  for (int i = 0; i < modules; ++i) {
    y << "  - name: m" << i << "\n    module: " << SYMB_SCENARIO_DIR << "/modules/cube.yaml\n";
    if (i == 0) y << "    start: {x: 0, y: 0, heading: 0}\n";
    y << "    tasks:\n      - {name: osc, type: oscillator, period: 20ms, params: {id: " << i
      << ", frequency: " << kFrequency << ", amplitude: " << kAmplitude << ", lag: " << kLag
      << ", coupling: " << kCoupling << ", initial_phase: " << initial_phase(i)
      << "}}\n    hooks:\n      - {from: osc, to: hinge, port: 0}\n";
    if (i > 0) y << "      - {from: osc, to: m" << i - 1 << "/osc, port: 1}\n";
    if (i + 1 < modules) y << "      - {from: osc, to: m" << i + 1 << "/osc, port: 1}\n";
  }
  const fs::path file = dir / ("organism_" + std::to_string(modules) + ".yaml");
  std::ofstream(file) << y.str();
  return file;
}

symb::sim::Scenario load(int modules) {
  auto sc = symb::sim::load_scenario(write_scenario(modules).string());
  if (!sc) throw std::runtime_error(sc.error());
  return std::move(sc).value();
}

// The framework: the scenario's OrganismSession on the virtual-time executor.
void BM_Framework(benchmark::State& state) {
  const int modules = static_cast<int>(state.range(0));
  const symb::sim::Scenario sc = load(modules);
  for (auto _ : state) {
    symb::kernel::VirtualTimeExecutor ex;
    auto made = symb::sim::mujoco::OrganismSession::create(sc, ex);
    if (!made) {
      state.SkipWithError(made.error().c_str());
      break;
    }
    (*made)->start();
    const double t0 = cpu_seconds();
    ex.run_for(sc.duration);
    const double wall = cpu_seconds() - t0;
    if (!(*made)->error().empty()) state.SkipWithError((*made)->error().c_str());
    state.SetIterationTime(wall);
    state.counters["rtf"] = symb::kernel::to_seconds(sc.duration) / wall;
  }
}

// Raw MuJoCo: the same modules, starts, model options and docks as the session builds, stepped in
// a plain loop with the oscillators called directly.
void BM_RawMujoco(benchmark::State& state) {
  const int modules = static_cast<int>(state.range(0));
  const symb::sim::Scenario sc = load(modules);
  const auto ticks = static_cast<long>(symb::kernel::to_seconds(sc.duration) / 0.02 + 0.5);
  for (auto _ : state) {
    std::vector<symb::sim::mujoco::ModuleSpec> specs;
    std::size_t connectors = 0;
    for (const auto& r : sc.robots) {
      specs.push_back({r.name, r.module_kind, r.module_start});
      connectors += r.module_kind.connectors.size();
    }
    symb::sim::mujoco::ModelOptions model;
    model.spare_welds = std::max<std::size_t>(1, connectors / 2);
    auto made = MujocoWorld::make(specs, model);
    if (!made) {
      state.SkipWithError(made.error().c_str());
      break;
    }
    MujocoWorld& w = made.value();
    for (const auto& d : sc.organism.docked) (void)w.latch(d.a, *w.find_connector(d.a, d.connector_a));
    std::vector<symb::control::cpg::PhaseOscillator> osc;
    for (int i = 0; i < modules; ++i) {
      osc.emplace_back(symb::control::cpg::OscillatorParams{.id = i,
                                                            .frequency = kFrequency,
                                                            .amplitude = kAmplitude,
                                                            .coupling = kCoupling,
                                                            .lag = kLag,
                                                            .initial_phase = initial_phase(i)});
      (void)w.set_wheels(static_cast<std::size_t>(i), 0, 0);
    }
    std::vector<double> phases(static_cast<std::size_t>(modules));
    const double t0 = cpu_seconds();
    for (long k = 0; k < ticks; ++k) {
      const double t = 0.02 * static_cast<double>(k);
      for (std::size_t i = 0; i < osc.size(); ++i) {
        osc[i].step(t);
        phases[i] = osc[i].phase();
        w.set_hinge_target(i, osc[i].output());
      }
      for (std::size_t i = 0; i < osc.size(); ++i) {
        if (i > 0) osc[i].hear(static_cast<int>(i) - 1, phases[i - 1], t);
        if (i + 1 < osc.size()) osc[i].hear(static_cast<int>(i) + 1, phases[i + 1], t);
      }
      if (auto st = w.step(kStepsPerTick); !st) {
        state.SkipWithError(st.error().c_str());
        break;
      }
    }
    const double wall = cpu_seconds() - t0;
    benchmark::DoNotOptimize(w.pose(0));
    state.SetIterationTime(wall);
    state.counters["rtf"] = static_cast<double>(ticks) * 0.02 / wall;
  }
}

void register_all() {
  for (int n : {5, 20, 50})
    for (auto [name, fn] : {std::pair{"BM_RawMujoco", &BM_RawMujoco}, std::pair{"BM_Framework", &BM_Framework}})
      benchmark::RegisterBenchmark(name, fn)->Arg(n)->Iterations(1)->Repetitions(5)->UseManualTime()->Unit(
          benchmark::kMillisecond);
}

}  // namespace

int main(int argc, char** argv) {
  register_all();
  symb::bench::CollectingReporter reporter(false);
  if (!symb::bench::run_interleaved(argc, argv, reporter)) return 1;
  std::error_code ignored;
  fs::remove_all(scenario_dir(), ignored);

  std::printf("\nreal-time factor (simulated s per CPU s), caterpillar chains, 20 ms control, median of repetitions\n");
  std::printf("%8s %12s %12s %10s\n", "modules", "raw MuJoCo", "framework", "ratio");
  double ratio5 = 0;
  for (int n : {5, 20, 50}) {
    const std::string a = "/" + std::to_string(n);
    const double raw = reporter.median("BM_RawMujoco" + a, "rtf");
    const double fw = reporter.median("BM_Framework" + a, "rtf");
    const double ratio = raw > 0 ? fw / raw : 0;
    if (n == 5) ratio5 = ratio;
    std::printf("%8d %12.1f %12.1f %9.0f%%\n", n, raw, fw, 100 * ratio);
  }
  for (const auto& e : reporter.errors()) std::printf("ERROR %s\n", e.c_str());
  const bool met = ratio5 >= kTarget5 && reporter.errors().empty();
  std::printf("organism: the framework at %.0f%% of raw MuJoCo for 5 modules (target >= %.0f%%): %s\n", 100 * ratio5,
              100 * kTarget5, met ? "MET" : "NOT MET");
  return 0;
}
