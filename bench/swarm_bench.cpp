// Large swarms (issue 17): real-time factor of 100, 1,000 and 10,000 Thymio IIs at equal density,
// each with the maze demo's MDL2e controller, on the 2-core reference box. One program, three
// columns measured in the same run, interleaved:
//   raw Enki    sim::EnkiWorld stepped in a loop, one mdl2e::Interpreter per robot called directly
//               (no node, task, hook or executor), one thread: the paper's engine as a person
//               would drive it without the framework. Enki's collision loop is quadratic, so at
//               1,000 and 10,000 robots it runs 100 and 3 steps only.
//   raw Box2D   the same loop on sim::Box2DWorld (Box2D 2.4 and the IR on a spatial grid), one
//               thread: the baseline of the framework's overhead.
//   symb run    the whole stack: apps::run::run_scenario on the box2d engine, the lockstep
//               executor with 2 worker threads, no output folder; timed from the run loop's first
//               look at the stop request to its last progress report, as `symb run` reports it.
// The worlds: a square arena of 4,000 cm^2 per robot with one 100 cm inner wall per 200 x 200 cm
// block on a checkerboard (so walls per robot are the same at every size), robots placed by the
// scenario's `start: random` from seed 1.
//
// Figures: real-time factor (simulated s per wall s; the raw loops' wall time is their thread's CPU
// time, so the box's other tenants do not count against them), the full stack's process CPU
// seconds per simulated second, and its heap per robot (mallinfo2, after the session is built).
// The scaling exponent is the slope of log(CPU per simulated second) against log(robots) from 100
// to 10,000. Targets: >= 10x real time at 1,000 robots, >= 1x at 10,000, exponent <= 1.1.
#include <malloc.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "symb/apps/run/scenario_run.hpp"
#include "symb/sim/scenario.hpp"

#include "bench_report.hpp"
#include "raw_world_mdl2e.hpp"

namespace {

namespace fs = std::filesystem;
using symb::bench::RawWorldMdl2e;
using symb::bench::thread_cpu_seconds;

constexpr double kCm2PerRobot = 4000;
constexpr double kBlock = 200;  // cm; one inner wall per two blocks
constexpr unsigned kThreads = 2;
constexpr double kTarget1000 = 10, kTarget10000 = 1, kTargetExponent = 1.1;
constexpr int kSizes[] = {100, 1000, 10000};

double process_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double wall_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// Simulated seconds per measured run: each side runs for one to a few seconds of wall clock. The
// 100-robot runs are the exponent's denominator: at 60 s (0.3 s of wall clock) one run's CPU time
// a simulated second moved by 10 % between runs, enough to flip the exponent's verdict; 300 s
// (about 1.5 s) holds it steadier.
double simulated_seconds(int robots) { return robots <= 100 ? 300 : robots <= 1000 ? 20 : 4; }
// Raw Enki's step is quadratic: about 80 ms at 1,000 robots and seconds at 10,000, so its rate
// there comes from a few steps.
int raw_enki_steps(int robots) {
  return robots >= 10000 ? 3 : robots >= 1000 ? 100 : static_cast<int>(std::lround(simulated_seconds(robots) / 0.03));
}

fs::path scenario_dir() { return fs::temp_directory_path() / ("symb_swarm_bench_" + std::to_string(::getpid())); }

fs::path write_scenario(int robots) {
  const fs::path dir = scenario_dir();
  const fs::path file = dir / ("swarm_" + std::to_string(robots) + ".yaml");
  if (fs::exists(file)) return file;
  fs::create_directories(dir / "mdl2e");
  fs::copy_file(fs::path(SYMB_SCENARIO_DIR) / "mdl2e" / "obstacle_avoidance.mdl2e",
                dir / "mdl2e" / "obstacle_avoidance.mdl2e", fs::copy_options::overwrite_existing);
  const double side = std::sqrt(kCm2PerRobot * robots);
  const int blocks = static_cast<int>(side / kBlock);
  std::ostringstream y;
  y << "name: swarm_" << robots << "\nseed: 1\nduration: " << simulated_seconds(robots)
    << "s\ncontrol_period: 30ms\nworld:\n  engine: box2d\n  arena: {width: " << side << ", height: " << side
    << "}\n  walls:\n";
  for (int bx = 0; bx < blocks; ++bx)
    for (int by = 0; by < blocks; ++by) {
      if ((bx + by) % 2 != 0) continue;
      const double x = bx * kBlock + kBlock / 2, y0 = by * kBlock + kBlock / 4;
      if (bx % 4 == 0)
        y << "    - [" << x << ", " << y0 << ", " << x << ", " << y0 + kBlock / 2 << "]\n";
      else
        y << "    - [" << x - kBlock / 4 << ", " << y0 + kBlock / 4 << ", " << x + kBlock / 4 << ", " << y0 + kBlock / 4
          << "]\n";
    }
  y << "robots:\n  - name: t\n    count: " << robots << "\n    start: random\n"
    << "    tasks:\n      - name: controller\n        type: mdl2e\n"
    << "        params: {program: mdl2e/obstacle_avoidance.mdl2e}\n"
    << "    hooks:\n      - ir -> controller -> wheels\n";
  std::ofstream(file) << y.str();
  return file;
}

const symb::sim::Scenario& scenario(int robots) { return symb::bench::parsed_scenario(write_scenario(robots)); }

void run_raw(benchmark::State& state, symb::sim::Engine2d engine) {
  const int robots = static_cast<int>(state.range(0));
  const symb::sim::Scenario& sc = scenario(robots);
  const int steps = engine == symb::sim::Engine2d::kEnki ? raw_enki_steps(robots)
                                                         : static_cast<int>(simulated_seconds(robots) / 0.03);
  double sum = 0;
  for (auto _ : state) {
    RawWorldMdl2e raw(sc, engine);
    raw.step();  // first step: every body and cache touched once
    const double t0 = thread_cpu_seconds();
    for (int i = 0; i < steps; ++i) raw.step();
    const double cpu = thread_cpu_seconds() - t0;
    sum += raw.checksum();
    state.SetIterationTime(cpu);
    state.counters["rtf"] = steps * 0.03 / cpu;
  }
  benchmark::DoNotOptimize(sum);
}

void BM_RawEnki(benchmark::State& state) { run_raw(state, symb::sim::Engine2d::kEnki); }
void BM_RawBox2d(benchmark::State& state) { run_raw(state, symb::sim::Engine2d::kBox2d); }

void BM_SymbRun(benchmark::State& state) {
  const int robots = static_cast<int>(state.range(0));
  const fs::path file = write_scenario(robots);
  for (auto _ : state) {
    double start_wall = -1, start_cpu = 0, end_wall = 0, end_cpu = 0, simulated = 0, heap = 0;
    symb::apps::run::RunOptions options;
    options.scenario_path = file.string();
    options.threads = kThreads;
    options.stop_requested = [&] {
      if (start_wall < 0) {
        const struct mallinfo2 m = mallinfo2();
        heap = static_cast<double>(m.uordblks + m.hblkhd);
        start_cpu = process_cpu_seconds();
        start_wall = wall_seconds();
      }
      return false;
    };
    options.on_progress = [&](const symb::apps::run::RunProgress& p) {
      end_wall = wall_seconds();
      end_cpu = process_cpu_seconds();
      simulated = p.simulated_seconds;
    };
    const struct mallinfo2 before = mallinfo2();
    auto result = symb::apps::run::run_scenario(options);
    if (!result) {
      state.SkipWithError(result.error().c_str());
      break;
    }
    if (!(start_wall >= 0 && end_wall > start_wall && simulated > 0)) {
      state.SkipWithError("the run loop reported no progress: nothing timed");
      break;
    }
    state.SetIterationTime(end_wall - start_wall);
    state.counters["rtf"] = simulated / (end_wall - start_wall);
    state.counters["cpu_per_sim_s"] = (end_cpu - start_cpu) / simulated;
    state.counters["heap_per_robot"] = (heap - static_cast<double>(before.uordblks + before.hblkhd)) / robots;
  }
}

void register_all() {
  for (int n : kSizes)
    for (auto [name, fn] : {std::pair{"BM_RawEnki", &BM_RawEnki}, std::pair{"BM_RawBox2d", &BM_RawBox2d},
                            std::pair{"BM_SymbRun", &BM_SymbRun}})
      benchmark::RegisterBenchmark(name, fn)
          ->Arg(n)
          ->Iterations(1)
          ->Repetitions(n >= 10000 && fn == &BM_RawEnki ? 1 : 3)
          ->UseManualTime()
          ->Unit(benchmark::kMillisecond);
}

}  // namespace

int main(int argc, char** argv) {
  register_all();
  symb::bench::CollectingReporter reporter(false);
  if (!symb::bench::run_interleaved(argc, argv, reporter)) return 1;
  std::error_code ignored;
  fs::remove_all(scenario_dir(), ignored);

  std::printf(
      "\nlarge swarms, equal density (4,000 cm^2 a robot), MDL2e controllers, dt 30 ms, median of repetitions\n");
  std::printf("%7s %10s %10s %18s %14s %16s %16s\n", "robots", "raw Enki", "raw Box2D", "symb run (2 thr)",
              "vs raw Box2D", "CPU s / sim s", "heap / robot");
  std::map<int, double> rtf, cpu, raw_box;
  for (int r : kSizes) {
    const std::string a = "/" + std::to_string(r);
    const double enki = reporter.median("BM_RawEnki" + a, "rtf");
    const double box = raw_box[r] = reporter.median("BM_RawBox2d" + a, "rtf");
    rtf[r] = reporter.median("BM_SymbRun" + a, "rtf");
    cpu[r] = reporter.median("BM_SymbRun" + a, "cpu_per_sim_s");
    const double heap = reporter.median("BM_SymbRun" + a, "heap_per_robot");
    std::printf("%7d %9.2fx %9.2fx %17.2fx %13.0f%% %16.3f %13.1f KiB\n", r, enki, box, rtf[r],
                box > 0 ? 100 * rtf[r] / box : 0.0, cpu[r], heap / 1024);
  }
  for (const auto& e : reporter.errors()) std::printf("ERROR %s\n", e.c_str());
  const double exponent =
      cpu[100] > 0 && cpu[10000] > 0 ? std::log(cpu[10000] / cpu[100]) / std::log(10000.0 / 100.0) : 0;
  // The raw Box2D loop's own exponent, from the CPU time of its thread per simulated second (the
  // inverse of its real-time factor): how the engine, the IR on its grid and the interpreters
  // scale with no framework at all, what the full stack's exponent is to be read against.
  const double raw_exponent =
      raw_box[100] > 0 && raw_box[10000] > 0 ? std::log(raw_box[100] / raw_box[10000]) / std::log(10000.0 / 100.0) : 0;
  const bool met = rtf[1000] >= kTarget1000 && rtf[10000] >= kTarget10000 && exponent > 0 &&
                   exponent <= kTargetExponent && reporter.errors().empty();
  std::printf(
      "swarm: symb run %.1fx real time at 1,000 robots (target >= %.0fx), %.2fx at 10,000 (target >= %.0fx), CPU "
      "time scaling exponent %.2f from 100 to 10,000 (target <= %.1f; raw Box2D's own %.2f): %s\n",
      rtf[1000], kTarget1000, rtf[10000], kTarget10000, exponent, kTargetExponent, raw_exponent,
      met ? "MET" : "NOT MET");
  return 0;
}
