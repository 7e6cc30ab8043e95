// Real-time factor of the whole framework in simulation (`symb run`: scenario, Enki world, world
// runner, one node per robot with ir -> MDL2e controller -> wheels, recorder) beside raw Enki
// stepping the same world under a hand-written Braitenberg loop, for 1, 10 and 100 robots. The
// worlds follow the reference benchmark (shared/reference/simulators.md 2.2): K x K cells of 50 cm,
// K = max(4, ceil(sqrt(2 N))), a DFS maze with 15 % of its walls knocked out, one robot per random
// cell with a random heading, dt = 30 ms, physics oversampling 1.
//
// Baselines, both with no framework at all (no node, task, hook, message or executor):
//   RawWorldMdl2e   the baseline of the targets, the same work as `symb run` minus the framework:
//                   the same world (sim::EnkiWorld: Enki physics, sim::IrModel for the IR, the
//                   same walls, starts and seed), the same controller (the maze demo's MDL2e
//                   program, one mdl2e::Interpreter per robot called directly with each step's IR
//                   at the step's time) and the same wheel mapping (speeds clamped to +-500 Thymio
//                   units, sent as float, scaled to cm/s), in a plain loop. The ratio against it
//                   is what the runtime costs.
//   RawEnki         information only: Enki's own Thymio2 IR and a hand-written Braitenberg loop,
//                   as the reference's enki_bench did: what a person writing against Enki alone
//                   would run.
// Framework: sim::ScenarioSession + the recorder, exactly what apps::run::run_scenario does, on the
// virtual-time executor, timed over the stepping only (as `symb run` reports it).
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <array>
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
#include <type_traits>
#include <vector>

#include <benchmark/benchmark.h>
#include <enki/PhysicalEngine.h>
#include <enki/robots/thymio2/Thymio2.h>

#include "symb/apps/run/scenario_run.hpp"
#include "symb/kernel/random_stream.hpp"
#include "symb/sim/enki_world.hpp"
#include "symb/sim/maze_generator.hpp"
#include "symb/sim/scenario.hpp"
#include "symb/sim/sim_drivers.hpp"
#include "symb/sim/world.hpp"

#include "bench_report.hpp"
#include "raw_world_mdl2e.hpp"

namespace {

namespace fs = std::filesystem;
using symb::bench::RawWorldMdl2e;
using symb::bench::thread_cpu_seconds;
using symb::sim::IrReadings;
using symb::sim::kIrCount;
using symb::sim::kIrMax;
using symb::sim::kMaxWheelSpeed;

constexpr double kDt = 0.03;
constexpr int kWarmupSteps = 33;
constexpr double kTarget1 = 0.90, kTarget100 = 0.95;
constexpr std::uint64_t kSeed = 1;

// Simulated seconds per measured run: long enough that each side runs for a good part of a second
// on the reference box, short enough that three repetitions of everything take about a minute.
double simulated_seconds(int robots) { return robots <= 1 ? 600 : robots <= 10 ? 120 : 20; }
int steps_for(int robots) { return static_cast<int>(std::lround(simulated_seconds(robots) / kDt)); }

struct BenchWorld {
  symb::sim::Maze maze;
  std::vector<symb::sim::Pose> starts;
};

const BenchWorld& bench_world(int robots) {
  static std::map<int, BenchWorld> cache;
  auto it = cache.find(robots);
  if (it != cache.end()) return it->second;
  symb::sim::MazeOptions mo;
  mo.cells = symb::sim::maze_cells_for_robots(static_cast<std::size_t>(robots));
  mo.seed = kSeed;
  auto maze = symb::sim::generate_maze(mo);
  if (!maze) throw std::runtime_error(maze.error());
  symb::kernel::RandomStream random(kSeed, 0x5354 /* "ST" */);
  auto starts = maze.value().random_starts(static_cast<std::size_t>(robots), random);
  if (!starts) throw std::runtime_error(starts.error());
  return cache.emplace(robots, BenchWorld{std::move(maze).value(), std::move(starts).value()}).first->second;
}

// The reference's Braitenberg controller on IR normalised by kIrMax: base 10 cm/s, the left
// sensors push the right wheel back and the right ones the left, a strong turn on the centre
// sensor, the rear sensors push forward.
void braitenberg(const double* ir, double& left, double& right) {
  double s[kIrCount];
  for (std::size_t i = 0; i < kIrCount; ++i) s[i] = ir[i] / kIrMax;
  const double base = 10, back = 6 * (s[5] + s[6]);
  const double from_left = 12 * s[0] + 8 * s[1], from_right = 8 * s[3] + 12 * s[4], front = 20 * s[2];
  left = base + back + from_left - from_right + front;
  right = base + back - from_left + from_right - front;
  left = std::clamp(left, -kMaxWheelSpeed, kMaxWheelSpeed);
  right = std::clamp(right, -kMaxWheelSpeed, kMaxWheelSpeed);
}

// Raw Enki: the world as the reference built it, Enki's square walls for the sides and each maze
// wall a static rectangle (the same geometry EnkiWorld builds), Enki's own IR.
class RawEnki {
 public:
  explicit RawEnki(int robots) : RawEnki(bench_world(robots)) {}
  explicit RawEnki(const BenchWorld& bw) : world_(bw.maze.world.width, bw.maze.world.height) {
    for (const symb::sim::WallSpec& s : bw.maze.world.walls) {
      const double dx = s.x2 - s.x1, dy = s.y2 - s.y1, length = std::hypot(dx, dy);
      auto* o = new Enki::PhysicalObject;
      o->setRectangular(length + s.thickness, s.thickness, bw.maze.world.wall_height, -1);
      o->pos = Enki::Point((s.x1 + s.x2) / 2, (s.y1 + s.y2) / 2);
      o->angle = length > 0 ? std::atan2(dy, dx) : 0.0;
      world_.addObject(o);
    }
    for (const symb::sim::Pose& p : bw.starts) {
      auto* r = new Enki::Thymio2;
      r->pos = Enki::Point(p.x, p.y);
      r->angle = p.theta;
      world_.addObject(r);
      robots_.push_back(r);
    }
  }

  void step() {
    for (Enki::Thymio2* r : robots_) {
      const Enki::IRSensor* s[kIrCount] = {&r->infraredSensor0, &r->infraredSensor1, &r->infraredSensor2,
                                           &r->infraredSensor3, &r->infraredSensor4, &r->infraredSensor5,
                                           &r->infraredSensor6};
      double v[kIrCount];
      for (std::size_t k = 0; k < kIrCount; ++k) v[k] = s[k]->getValue();
      braitenberg(v, r->leftSpeed, r->rightSpeed);
    }
    world_.step(kDt, 1);
  }

  // Sum of the positions, so the compiler cannot drop the work.
  double checksum() const {
    double s = 0;
    for (const Enki::Thymio2* r : robots_) s += r->pos.x + r->pos.y;
    return s;
  }

 private:
  Enki::World world_;  // owns the objects added to it
  std::vector<Enki::Thymio2*> robots_;
};

fs::path write_scenario(int robots);

// The bench's scenario file for `robots`, parsed as `symb run` parses it.
const symb::sim::Scenario& bench_scenario(int robots) { return symb::bench::parsed_scenario(write_scenario(robots)); }

template <class Raw>
Raw make_raw(int robots) {
  if constexpr (std::is_same_v<Raw, RawWorldMdl2e>)
    return Raw(bench_scenario(robots));
  else
    return Raw(robots);
}

template <class Raw>
void run_raw(benchmark::State& state) {
  const int robots = static_cast<int>(state.range(0));
  const int steps = steps_for(robots);
  (void)bench_world(robots);  // built before the clock starts
  double sum = 0;
  for (auto _ : state) {
    Enki::random.setSeed(static_cast<unsigned long>(kSeed));
    std::srand(static_cast<unsigned>(kSeed));
    Raw raw = make_raw<Raw>(robots);
    for (int i = 0; i < kWarmupSteps; ++i) raw.step();
    const double t0 = thread_cpu_seconds();
    for (int i = 0; i < steps; ++i) raw.step();
    const double cpu = thread_cpu_seconds() - t0;
    sum += raw.checksum();
    state.SetIterationTime(cpu);
    state.counters["rtf"] = steps * kDt / cpu;
  }
  benchmark::DoNotOptimize(sum);
}

void BM_RawEnki(benchmark::State& state) { run_raw<RawEnki>(state); }
void BM_RawWorldMdl2e(benchmark::State& state) { run_raw<RawWorldMdl2e>(state); }

// The scenario file for the bench world: the maze's walls, one robot entry per start, each with
// the maze demo's control system.
fs::path scenario_dir() { return fs::temp_directory_path() / ("symb_sim_rtf_bench_" + std::to_string(::getpid())); }

fs::path write_scenario(int robots) {
  const BenchWorld& bw = bench_world(robots);
  const fs::path dir = scenario_dir();
  fs::create_directories(dir / "mdl2e");
  fs::copy_file(fs::path(SYMB_SCENARIO_DIR) / "mdl2e" / "obstacle_avoidance.mdl2e",
                dir / "mdl2e" / "obstacle_avoidance.mdl2e", fs::copy_options::overwrite_existing);
  std::ostringstream y;
  y.precision(17);
  y << "name: bench_" << robots << "\nseed: " << kSeed << "\nduration: " << simulated_seconds(robots)
    << "s\ncontrol_period: 30ms\nworld:\n  arena: {width: " << bw.maze.world.width
    << ", height: " << bw.maze.world.height << "}\n  wall_height: " << bw.maze.world.wall_height << "\n";
  if (!bw.maze.world.walls.empty()) {
    y << "  walls:\n";
    for (const symb::sim::WallSpec& w : bw.maze.world.walls)
      y << "    - {from: [" << w.x1 << ", " << w.y1 << "], to: [" << w.x2 << ", " << w.y2
        << "], thickness: " << w.thickness << "}\n";
  }
  y << "robots:\n  - name: thymio\n    count: " << robots << "\n    start:\n";
  for (const symb::sim::Pose& p : bw.starts)
    y << "      - {x: " << p.x << ", y: " << p.y << ", heading: " << p.theta * 180 / M_PI << "}\n";
  y << "    tasks:\n      - name: controller\n        type: mdl2e\n"
    << "        params: {program: mdl2e/obstacle_avoidance.mdl2e}\n"
    << "    hooks:\n      - ir -> controller -> wheels\n";
  const fs::path file = dir / ("bench_" + std::to_string(robots) + ".yaml");
  std::ofstream(file) << y.str();
  return file;
}

void BM_SymbRun(benchmark::State& state) {
  const int robots = static_cast<int>(state.range(0));
  const fs::path file = write_scenario(robots);
  for (auto _ : state) {
    // Timed in the thread's CPU time from the run loop's first look at the stop request (the
    // session built and started) to its last progress report (the end of the run): the stepping,
    // not the reading and building of the scenario, as `symb run` reports its real-time factor.
    double start_cpu = -1, end_cpu = 0, simulated = 0;
    symb::apps::run::RunOptions options;
    options.scenario_path = file.string();
    options.stop_requested = [&] {
      if (start_cpu < 0) start_cpu = thread_cpu_seconds();
      return false;
    };
    options.on_progress = [&](const symb::apps::run::RunProgress& p) {
      end_cpu = thread_cpu_seconds();
      simulated = p.simulated_seconds;
    };
    auto result = symb::apps::run::run_scenario(options);
    if (!result) {
      state.SkipWithError(result.error().c_str());
      break;
    }
    if (!(start_cpu >= 0 && end_cpu > start_cpu && simulated > 0)) {
      state.SkipWithError("the run loop reported no progress: nothing timed");
      break;
    }
    state.SetIterationTime(end_cpu - start_cpu);
    state.counters["rtf"] = simulated / (end_cpu - start_cpu);
  }
}

// Whether the baseline does the same work: run the scenario once through `symb run` and the
// baseline for the same number of steps, and compare where every robot ends, bit for bit.
bool same_trajectories(int robots, std::string& why) {
  symb::apps::run::RunOptions options;
  options.scenario_path = write_scenario(robots).string();
  auto result = symb::apps::run::run_scenario(options);
  if (!result) {
    why = result.error();
    return false;
  }
  RawWorldMdl2e raw(bench_scenario(robots));
  for (std::uint64_t i = 0; i < result.value().steps; ++i) raw.step();
  for (std::size_t i = 0; i < result.value().robots.size(); ++i) {
    const symb::sim::Pose a = raw.pose(i), b = result.value().robots[i].end;
    if (a.x != b.x || a.y != b.y || a.theta != b.theta) {
      why = "robot " + std::to_string(i) + " ends at " + std::to_string(a.x) + "," + std::to_string(a.y) +
            ", symb run at " + std::to_string(b.x) + "," + std::to_string(b.y) + " after " +
            std::to_string(result.value().steps) + " steps";
      return false;
    }
  }
  return true;
}

void register_all() {
  for (int n : {1, 10, 100}) {
    for (auto [name, fn] : {std::pair{"BM_RawEnki", &BM_RawEnki}, std::pair{"BM_RawWorldMdl2e", &BM_RawWorldMdl2e},
                            std::pair{"BM_SymbRun", &BM_SymbRun}})
      benchmark::RegisterBenchmark(name, fn)->Arg(n)->Iterations(1)->Repetitions(3)->UseManualTime()->Unit(
          benchmark::kMillisecond);
  }
}

}  // namespace

int main(int argc, char** argv) {
  register_all();
  std::string why;
  const bool same = same_trajectories(10, why);
  symb::bench::CollectingReporter reporter(false);
  if (!symb::bench::run_interleaved(argc, argv, reporter)) return 1;
  std::error_code ignored;
  fs::remove_all(scenario_dir(), ignored);

  std::printf(
      "\nreal-time factor (simulated s per CPU s of the running thread), reference maze worlds, dt 30 ms, median of "
      "repetitions\n");
  std::printf("%7s %18s %12s %20s %12s\n", "robots", "raw world+MDL2e", "symb run", "vs raw world+MDL2e",
              "raw Enki (info)");
  double ratio1 = 0, ratio100 = 0;
  for (int r : {1, 10, 100}) {
    const std::string a = "/" + std::to_string(r);
    const double raw = reporter.median("BM_RawWorldMdl2e" + a, "rtf");
    const double enki = reporter.median("BM_RawEnki" + a, "rtf");
    const double fw = reporter.median("BM_SymbRun" + a, "rtf");
    const double ratio = raw > 0 ? fw / raw : 0;
    if (r == 1) ratio1 = ratio;
    if (r == 100) ratio100 = ratio;
    std::printf("%7d %18.1f %12.1f %19.0f%% %12.1f\n", r, raw, fw, 100 * ratio, enki);
  }
  std::printf("baseline and symb run, 10 robots, 120 s: the robots end at the same poses, bit for bit: %s\n",
              same ? "yes" : ("NO (" + why + ")").c_str());
  for (const auto& e : reporter.errors()) std::printf("ERROR %s\n", e.c_str());
  const bool met = ratio1 >= kTarget1 && ratio100 >= kTarget100 && reporter.errors().empty() && same;
  std::printf(
      "sim_rtf: symb run at %.0f%% of the raw world with the same MDL2e controller for 1 robot (target >= %.0f%%), "
      "%.0f%% for 100 robots (target >= %.0f%%): %s\n",
      100 * ratio1, 100 * kTarget1, 100 * ratio100, 100 * kTarget100, met ? "MET" : "NOT MET");
  return 0;
}
