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
// Framework: apps::run::run_scenario on the scenario file the bench writes, exactly `symb run`
// minus writing files, timed over the stepping only (as `symb run` reports it).
// Measurement: each repetition of a case is a process of its own (a fresh heap for both sides, see
// run_pair_process) that runs `symb run` and the baseline interleaved a simulated second at a time
// on one thread (see measure_pair); the ratio is the median over the repetitions.
#include <spawn.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <benchmark/benchmark.h>
#include <enki/PhysicalEngine.h>
#include <enki/robots/thymio2/Thymio2.h>

#include "symb/apps/run/scenario_run.hpp"
#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/result.hpp"
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

// Raw Enki (information only), in this process: its figure is not part of a ratio.
void BM_RawEnki(benchmark::State& state) {
  const int robots = static_cast<int>(state.range(0));
  const int steps = steps_for(robots);
  (void)bench_world(robots);  // built before the clock starts
  double sum = 0;
  for (auto _ : state) {
    Enki::random.setSeed(static_cast<unsigned long>(kSeed));
    std::srand(static_cast<unsigned>(kSeed));
    RawEnki raw(robots);
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

// What one repetition measured: each side's CPU seconds over its own slices, and the simulated
// seconds `symb run` reported.
struct PairTimes {
  double raw_cpu = 0, symb_cpu = 0, simulated = 0;
};

// One repetition, in a process of its own (pair_child): `symb run` on the scenario file and the
// baseline (raw world + MDL2e) on the same scenario, interleaved slice by slice on this thread. The
// run loop asks whether to stop before each of its slices (one simulated second), and there the
// baseline is stepped up to the simulated time `symb run` has reached. Each side is timed in this
// thread's CPU time over its own slices only, so a burst of load from the box's other tenants,
// which lasts longer than a slice, falls on both sides alike. `symb run` is timed from the loop's
// first look at the stop request (the session built and started) to its last progress report (the
// end of the run), as it reports its real-time factor. With `raw_first` the baseline's world is
// built before the session, otherwise right after it (at the first look at the stop request);
// the parent alternates the two.
symb::kernel::Result<PairTimes> measure_pair(int robots, bool raw_first, const fs::path& file) {
  const int steps = steps_for(robots);
  Enki::random.setSeed(static_cast<unsigned long>(kSeed));
  std::srand(static_cast<unsigned>(kSeed));
  std::optional<RawWorldMdl2e> raw;
  const auto build_raw = [&] {
    raw.emplace(symb::bench::parsed_scenario(file));
    for (int i = 0; i < kWarmupSteps; ++i) raw->step();
  };
  if (raw_first) build_raw();
  PairTimes t;
  int raw_steps = 0, slices = 0;
  double mark = -1;
  // The baseline up to `seconds` of simulated time, timed on its own.
  const auto raw_until = [&](double seconds) {
    if (!raw) build_raw();
    const int target = std::min(steps, static_cast<int>(std::floor(seconds / kDt + 1e-9)));
    const double t0 = thread_cpu_seconds();
    for (; raw_steps < target; ++raw_steps) raw->step();
    t.raw_cpu += thread_cpu_seconds() - t0;
  };
  symb::apps::run::RunOptions options;
  options.scenario_path = file.string();
  options.stop_requested = [&] {
    if (mark >= 0) t.symb_cpu += thread_cpu_seconds() - mark;
    raw_until(static_cast<double>(slices++));  // the run loop's slices are one simulated second
    mark = thread_cpu_seconds();
    return false;
  };
  options.on_progress = [&](const symb::apps::run::RunProgress& p) {
    const double now = thread_cpu_seconds();
    if (mark >= 0) t.symb_cpu += now - mark;
    mark = thread_cpu_seconds();
    t.simulated = p.simulated_seconds;
  };
  auto result = symb::apps::run::run_scenario(options);
  if (!result) return symb::kernel::Error{result.error()};
  raw_until(steps * kDt);
  if (!(t.symb_cpu > 0 && t.raw_cpu > 0 && t.simulated > 0 && raw_steps == steps))
    return symb::kernel::Error{"the run loop reported no progress: nothing timed"};
  benchmark::DoNotOptimize(raw->checksum());
  return t;
}

constexpr const char* kChildFlag = "--sim-rtf-pair=";

// A repetition's process: `bench_sim_rtf --sim-rtf-pair=ROBOTS,RAW_FIRST,FILE` prints the three
// figures on one line (or `error: ...`) and exits.
int pair_child(std::string_view spec) {
  int robots = 0, raw_first = 0, consumed = 0;
  const std::string text(spec);
  if (std::sscanf(text.c_str(), "%d,%d,%n", &robots, &raw_first, &consumed) != 2 || consumed == 0 || robots < 1 ||
      static_cast<std::size_t>(consumed) >= text.size()) {
    std::printf("error: bad %s%s\n", kChildFlag, text.c_str());
    return 2;
  }
  symb::kernel::Result<PairTimes> t = symb::kernel::Error{"not run"};
  try {  // the bench's helpers throw on a scenario they cannot read
    t = measure_pair(robots, raw_first != 0, text.substr(static_cast<std::size_t>(consumed)));
  } catch (const std::exception& e) {
    t = symb::kernel::Error{e.what()};
  }
  if (!t) {
    std::printf("error: %s\n", t.error().c_str());
    return 1;
  }
  std::printf("%.9f %.9f %.9f\n", t.value().raw_cpu, t.value().symb_cpu, t.value().simulated);
  return 0;
}

// Runs one repetition in a fresh process of this program. A world's speed depends on where its
// objects lie in the heap (Enki walks its objects through a std::set of pointers, every pair of
// them every step): built in the same process after another run was freed, the baseline's world
// at 100 robots ran 25 % slower than built first, which swung the ratio between 88 % and 118 %
// with the same code. A fresh process gives both sides a fresh heap, as `symb run` has.
symb::kernel::Result<PairTimes> run_pair_process(const std::string& self, int robots, bool raw_first,
                                                 const fs::path& file) {
  const std::string arg =
      std::string(kChildFlag) + std::to_string(robots) + "," + (raw_first ? "1" : "0") + "," + file.string();
  int out[2];
  if (::pipe(out) != 0) return symb::kernel::Error{"pipe failed"};
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, out[1], STDOUT_FILENO);
  posix_spawn_file_actions_addclose(&actions, out[0]);
  char* argv[] = {const_cast<char*>(self.c_str()), const_cast<char*>(arg.c_str()), nullptr};
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, self.c_str(), &actions, nullptr, argv, environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(out[1]);
  std::string text;
  char buf[512];
  for (ssize_t n; (n = ::read(out[0], buf, sizeof buf)) > 0;) text.append(buf, static_cast<std::size_t>(n));
  ::close(out[0]);
  if (spawned != 0) return symb::kernel::Error{"cannot start " + self + ": " + std::strerror(spawned)};
  int status = 0;
  ::waitpid(pid, &status, 0);
  // The figures are the last line (whatever the run printed before it).
  const std::size_t end = text.find_last_not_of('\n');
  const std::size_t last = end == std::string::npos ? 0 : text.find_last_of('\n', end);
  const std::string line = end == std::string::npos ? "" : text.substr(last == std::string::npos ? 0 : last + 1);
  PairTimes t;
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 ||
      std::sscanf(line.c_str(), "%lf %lf %lf", &t.raw_cpu, &t.symb_cpu, &t.simulated) != 3)
    return symb::kernel::Error{"repetition process for " + std::to_string(robots) +
                               " robots: " + (text.empty() ? std::string("no output") : text)};
  return t;
}

// `self`: this program, for its repetition processes; `done`: the case's repetitions so far, whose
// count alternates the order in which the two sides are built.
void BM_Pair(benchmark::State& state, const std::string& self, int& done) {
  const int robots = static_cast<int>(state.range(0));
  const fs::path file = write_scenario(robots);
  for (auto _ : state) {
    const bool raw_first = done++ % 2 == 0;
    auto t = run_pair_process(self, robots, raw_first, file);
    if (!t) {
      state.SkipWithError(t.error().c_str());
      break;
    }
    state.SetIterationTime(t.value().raw_cpu + t.value().symb_cpu);
    const double raw_rtf = steps_for(robots) * kDt / t.value().raw_cpu;
    const double symb_rtf = t.value().simulated / t.value().symb_cpu;
    state.counters["raw_rtf"] = raw_rtf;
    state.counters["symb_rtf"] = symb_rtf;
    state.counters["ratio"] = symb_rtf / raw_rtf;
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

// Repetitions of a case: enough that the median of the ratios moves by about a point from one run
// of the program to the next on the shared box, and the whole program stays under half a minute.
int pairs_for(int robots) { return robots <= 10 ? 9 : 5; }

void register_all(const std::string& self) {
  for (int n : {1, 10, 100}) {
    benchmark::RegisterBenchmark(
        "BM_Pair", [self, done = std::make_shared<int>(0)](benchmark::State& state) { BM_Pair(state, self, *done); })
        ->Arg(n)
        ->Iterations(1)
        ->Repetitions(pairs_for(n))
        ->UseManualTime()
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark("BM_RawEnki", BM_RawEnki)
        ->Arg(n)
        ->Iterations(1)
        ->Repetitions(3)
        ->UseManualTime()
        ->Unit(benchmark::kMillisecond);
  }
}

// The value at quantile q of `v` (sorted here), by linear interpolation.
double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const double at = q * static_cast<double>(v.size() - 1);
  const std::size_t lo = static_cast<std::size_t>(at);
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (at - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 2 && std::string_view(argv[1]).starts_with(kChildFlag))
    return pair_child(std::string_view(argv[1]).substr(std::string_view(kChildFlag).size()));
  register_all(fs::read_symlink("/proc/self/exe").string());
  std::string why;
  const bool same = same_trajectories(10, why);
  symb::bench::CollectingReporter reporter(false);
  if (!symb::bench::run_interleaved(argc, argv, reporter)) return 1;
  std::error_code ignored;
  fs::remove_all(scenario_dir(), ignored);

  std::printf(
      "\nreal-time factor (simulated s per CPU s of the running thread), reference maze worlds, dt 30 ms; each "
      "repetition runs the baseline and symb run interleaved, a simulated second at a time; the ratio is the median "
      "over the repetitions (quartiles in brackets)\n");
  std::printf("%7s %6s %18s %12s %26s %16s\n", "robots", "reps", "raw world+MDL2e", "symb run", "vs raw world+MDL2e",
              "raw Enki (info)");
  double ratio1 = 0, ratio100 = 0;
  for (int r : {1, 10, 100}) {
    const std::string pair = "BM_Pair/" + std::to_string(r);
    const std::vector<double> ratios = reporter.samples(pair, "ratio");
    const double ratio = quantile(ratios, 0.5);
    if (r == 1) ratio1 = ratio;
    if (r == 100) ratio100 = ratio;
    std::printf("%7d %6zu %18.1f %12.1f %11.1f%% [%4.1f, %4.1f] %16.1f\n", r, ratios.size(),
                reporter.median(pair, "raw_rtf"), reporter.median(pair, "symb_rtf"), 100 * ratio,
                100 * quantile(ratios, 0.25), 100 * quantile(ratios, 0.75),
                reporter.median("BM_RawEnki/" + std::to_string(r), "rtf"));
  }
  std::printf("baseline and symb run, 10 robots, 120 s: the robots end at the same poses, bit for bit: %s\n",
              same ? "yes" : ("NO (" + why + ")").c_str());
  for (const auto& e : reporter.errors()) std::printf("ERROR %s\n", e.c_str());
  const bool met = ratio1 >= kTarget1 && ratio100 >= kTarget100 && reporter.errors().empty() && same;
  std::printf(
      "sim_rtf: symb run at %.1f%% of the raw world with the same MDL2e controller for 1 robot (target >= %.0f%%), "
      "%.1f%% for 100 robots (target >= %.0f%%): %s\n",
      100 * ratio1, 100 * kTarget1, 100 * ratio100, 100 * kTarget100, met ? "MET" : "NOT MET");
  return 0;
}
