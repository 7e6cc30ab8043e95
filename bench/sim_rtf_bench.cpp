// Real-time factor of the whole framework in simulation (`symb run`: scenario, Enki world, world
// runner, one node per robot with ir -> MDL2e controller -> wheels, recorder) beside raw Enki
// stepping the same world under a hand-written Braitenberg loop, for 1, 10 and 100 robots. The
// worlds follow the reference benchmark (shared/reference/simulators.md 2.2): K x K cells of 50 cm,
// K = max(4, ceil(sqrt(2 N))), a DFS maze with 15 % of its walls knocked out, one robot per random
// cell with a random heading, dt = 30 ms, physics oversampling 1.
//
// Baselines, both stepping Enki directly with no framework at all:
//   RawEnki         Enki's own Thymio2 IR, as the reference's enki_bench did: what a person
//                   writing against Enki alone would run. This is the baseline of the targets.
//   RawEnkiIrModel  Enki physics with Enki's IR switched off and sim::IrModel instead, the sensor
//                   model the framework uses (Enki 1.6.99's IR goes stale, see ir_model.hpp): the
//                   ratio against it is the framework's own cost, sensors aside.
// Framework: sim::ScenarioSession + the recorder, exactly what apps::run::run_scenario does, on the
// virtual-time executor, timed over the stepping only (as `symb run` reports it).
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
#include <enki/PhysicalEngine.h>
#include <enki/robots/thymio2/Thymio2.h>

#include "symb/apps/run/scenario_run.hpp"
#include "symb/kernel/random_stream.hpp"
#include "symb/sim/ir_model.hpp"
#include "symb/sim/maze_generator.hpp"
#include "symb/sim/world.hpp"

#include "bench_report.hpp"

namespace {

namespace fs = std::filesystem;
using symb::sim::IrReadings;
using symb::sim::kIrCount;
using symb::sim::kIrMax;
using symb::sim::kMaxWheelSpeed;

constexpr double kDt = 0.03;
constexpr int kWarmupSteps = 33;
constexpr double kTarget1 = 0.80, kTarget100 = 0.90;
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

// Enki's Thymio2 with its IR interactions removed (they are protected), as EnkiWorld does.
class ThymioWithoutIr final : public Enki::Thymio2 {
 public:
  ThymioWithoutIr() { localInteractions.clear(); }
};

// Raw Enki: the world as the reference built it, Enki's square walls for the sides and each maze
// wall a static rectangle (the same geometry EnkiWorld builds).
class RawEnki {
 public:
  RawEnki(const BenchWorld& bw, bool enki_ir) : world_(bw.maze.world.width, bw.maze.world.height), enki_ir_(enki_ir) {
    std::vector<symb::sim::IrModel::Rect> rects;
    for (const symb::sim::WallSpec& s : bw.maze.world.walls) {
      const double dx = s.x2 - s.x1, dy = s.y2 - s.y1, length = std::hypot(dx, dy);
      auto* o = new Enki::PhysicalObject;
      o->setRectangular(length + s.thickness, s.thickness, bw.maze.world.wall_height, -1);
      o->pos = Enki::Point((s.x1 + s.x2) / 2, (s.y1 + s.y2) / 2);
      o->angle = length > 0 ? std::atan2(dy, dx) : 0.0;
      world_.addObject(o);
      rects.push_back({o->pos.x, o->pos.y, (length + s.thickness) / 2, s.thickness / 2, o->angle});
    }
    // The sides, for the IR model (Enki's own walls are not objects).
    const double w = bw.maze.world.width, h = bw.maze.world.height, t = 1;
    rects.push_back({w / 2, -t / 2, w / 2 + t, t / 2, 0});
    rects.push_back({w / 2, h + t / 2, w / 2 + t, t / 2, 0});
    rects.push_back({-t / 2, h / 2, t / 2, h / 2 + t, 0});
    rects.push_back({w + t / 2, h / 2, t / 2, h / 2 + t, 0});
    for (const symb::sim::Pose& p : bw.starts) {
      Enki::Thymio2* r = enki_ir_ ? new Enki::Thymio2 : new ThymioWithoutIr;
      r->pos = Enki::Point(p.x, p.y);
      r->angle = p.theta;
      world_.addObject(r);
      robots_.push_back(r);
    }
    if (!enki_ir_) ir_model_ = std::make_unique<symb::sim::IrModel>(std::move(rects));
    poses_.resize(robots_.size());
    ir_.resize(robots_.size());
  }

  void step() {
    for (std::size_t i = 0; i < robots_.size(); ++i) {
      Enki::Thymio2* r = robots_[i];
      double v[kIrCount];
      if (enki_ir_) {
        const Enki::IRSensor* s[kIrCount] = {&r->infraredSensor0, &r->infraredSensor1, &r->infraredSensor2,
                                             &r->infraredSensor3, &r->infraredSensor4, &r->infraredSensor5,
                                             &r->infraredSensor6};
        for (std::size_t k = 0; k < kIrCount; ++k) v[k] = s[k]->getValue();
      } else {
        for (std::size_t k = 0; k < kIrCount; ++k) v[k] = ir_[i][k];
      }
      braitenberg(v, r->leftSpeed, r->rightSpeed);
    }
    world_.step(kDt, 1);
    if (!enki_ir_) {
      for (std::size_t i = 0; i < robots_.size(); ++i)
        poses_[i] = symb::sim::Pose{robots_[i]->pos.x, robots_[i]->pos.y, robots_[i]->angle};
      ir_model_->set_robots(poses_);
      for (std::size_t i = 0; i < robots_.size(); ++i) ir_[i] = ir_model_->read(i, noise_);
    }
  }

  // Sum of the positions, so the compiler cannot drop the work.
  double checksum() const {
    double s = 0;
    for (const Enki::Thymio2* r : robots_) s += r->pos.x + r->pos.y;
    return s;
  }

 private:
  Enki::World world_;  // owns the objects added to it
  bool enki_ir_;
  std::vector<Enki::Thymio2*> robots_;
  std::unique_ptr<symb::sim::IrModel> ir_model_;
  std::vector<symb::sim::Pose> poses_;
  std::vector<IrReadings> ir_;
  symb::kernel::RandomStream noise_{kSeed, 0x4952};
};

void run_raw(benchmark::State& state, bool enki_ir) {
  const int robots = static_cast<int>(state.range(0));
  const int steps = steps_for(robots);
  const BenchWorld& bw = bench_world(robots);
  double sum = 0;
  for (auto _ : state) {
    Enki::random.setSeed(static_cast<unsigned long>(kSeed));
    std::srand(static_cast<unsigned>(kSeed));
    RawEnki raw(bw, enki_ir);
    for (int i = 0; i < kWarmupSteps; ++i) raw.step();
    const auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < steps; ++i) raw.step();
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    sum += raw.checksum();
    state.SetIterationTime(wall);
    state.counters["rtf"] = steps * kDt / wall;
  }
  benchmark::DoNotOptimize(sum);
}

void BM_RawEnki(benchmark::State& state) { run_raw(state, true); }
void BM_RawEnkiIrModel(benchmark::State& state) { run_raw(state, false); }

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
    symb::apps::run::RunOptions options;
    options.scenario_path = file.string();
    auto result = symb::apps::run::run_scenario(options);
    if (!result) {
      state.SkipWithError(result.error().c_str());
      break;
    }
    state.SetIterationTime(result.value().wall_seconds);
    state.counters["rtf"] = result.value().real_time_factor;
  }
}

void register_all() {
  for (int n : {1, 10, 100}) {
    for (auto [name, fn] : {std::pair{"BM_RawEnki", &BM_RawEnki}, std::pair{"BM_RawEnkiIrModel", &BM_RawEnkiIrModel},
                            std::pair{"BM_SymbRun", &BM_SymbRun}})
      benchmark::RegisterBenchmark(name, fn)->Arg(n)->Iterations(1)->Repetitions(3)->UseManualTime()->Unit(
          benchmark::kMillisecond);
  }
}

}  // namespace

int main(int argc, char** argv) {
  register_all();
  symb::bench::CollectingReporter reporter(false);
  if (!symb::bench::run_interleaved(argc, argv, reporter)) return 1;
  std::error_code ignored;
  fs::remove_all(scenario_dir(), ignored);

  std::printf("\nreal-time factor (simulated s per wall s), reference maze worlds, dt 30 ms, median of repetitions\n");
  std::printf("%7s %12s %16s %12s %16s %16s\n", "robots", "raw Enki", "raw Enki+IrModel", "symb run", "vs raw Enki",
              "vs raw+IrModel");
  double ratio1 = 0, ratio100 = 0;
  for (int r : {1, 10, 100}) {
    const std::string a = "/" + std::to_string(r);
    const double raw = reporter.median("BM_RawEnki" + a, "rtf");
    const double raw_ir = reporter.median("BM_RawEnkiIrModel" + a, "rtf");
    const double fw = reporter.median("BM_SymbRun" + a, "rtf");
    const double ratio = raw > 0 ? fw / raw : 0;
    if (r == 1) ratio1 = ratio;
    if (r == 100) ratio100 = ratio;
    std::printf("%7d %12.1f %16.1f %12.1f %15.0f%% %15.0f%%\n", r, raw, raw_ir, fw, 100 * ratio,
                raw_ir > 0 ? 100 * fw / raw_ir : 0.0);
  }
  for (const auto& e : reporter.errors()) std::printf("ERROR %s\n", e.c_str());
  const bool met = ratio1 >= kTarget1 && ratio100 >= kTarget100 && reporter.errors().empty();
  std::printf(
      "sim_rtf: symb run at %.0f%% of raw Enki for 1 robot (target >= %.0f%%), %.0f%% for 100 robots "
      "(target >= %.0f%%): %s\n",
      100 * ratio1, 100 * kTarget1, 100 * ratio100, 100 * kTarget100, met ? "MET" : "NOT MET");
  return 0;
}
