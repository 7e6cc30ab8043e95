// Evaluations per second of the maze (1+1)-ONLINE run on one core (issue 7, Benchmark): the
// framework (sim::ScenarioSession on the maze of scenarios/maze.yaml with its controller removed,
// a `fitness` task hooked from the IR (a report every 5 steps, as in scenarios/evolve_maze.yaml),
// a `one_plus_one` task swapping a new mlp controller TASK
// per candidate, exactly as tests/sim/evolution_scenario_test.cpp runs it) beside the same loop
// with no framework at all, in the same run:
//
//   RawEnkiLoop  an Enki::World with the maze's walls (static rectangles, the geometry EnkiWorld
//                builds) and one Thymio2 with Enki's IR removed; the 7 IR values from
//                sim::IrModel (the framework's sensor model, as bench_sim_rtf's second baseline);
//                the 7-2 tanh perceptron computed inline on IR / 4505, outputs x 500 (the mlp
//                task's math), turned into cm/s as the simulated wheels do; the per-step fitness
//                from evo::fitness_step (formula one_plus_one, the command driven since the last
//                reading, as the fitness task pairs them); the same evo::OnePlusOne object
//                stepping through evaluations of 1 s recovery + 20 s counted at dt = 30 ms.
//
// Both run the same virtual time (kVirtual) from the same start, seed and parameters, interleaved
// minute by minute (BM_Interleaved); the figure is evaluations per CPU second of the (single)
// thread they run on. The ratio framework / raw is the framework's cost for an evolution run
// (tasks, hooks, messages, the controller swap per candidate): the median over the repetitions.
// Target >= 80 %.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <enki/PhysicalEngine.h>
#include <enki/robots/thymio2/Thymio2.h>

#include "symb/evo/fitness/fitness.hpp"
#include "symb/evo/fitness/fitness_task.hpp"
#include "symb/evo/one_plus_one/one_plus_one.hpp"
#include "symb/evo/one_plus_one/one_plus_one_task.hpp"
#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/sim/ir_model.hpp"
#include "symb/sim/scenario_session.hpp"

#include "bench_report.hpp"

namespace {

using namespace std::chrono_literals;
using symb::sim::kIrCount;

constexpr double kDt = 0.03;
constexpr symb::kernel::Duration kVirtual = 60min;  // about 171 evaluations of 21 s
constexpr symb::kernel::Duration kEvaluation = 20s, kRecovery = 1s;
constexpr double kSigmaMin = 0.05;
constexpr std::uint64_t kFirstSeed = 1;  // repetition r runs seed kFirstSeed + r on every side
constexpr double kTarget = 0.80;
constexpr int kRepetitions = 7;
constexpr symb::kernel::Duration kSlice = 1min;  // of virtual time per side and turn (BM_Interleaved)

// CPU seconds of this process: the box is shared and loaded, wall time would count the time the
// scheduler gave to other jobs. Both sides run on this thread only (virtual-time executor).
double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

symb::sim::Scenario bare_maze() {
  auto s = symb::sim::load_scenario(std::string(SYMB_SCENARIO_DIR) + "/maze.yaml");
  if (!s) throw std::runtime_error(s.error());
  symb::sim::Scenario scenario = std::move(s).value();
  for (symb::sim::RobotSpec& r : scenario.robots) {
    r.tasks.clear();
    r.hooks.clear();
  }
  return scenario;
}

// As scenarios/evolve_maze.yaml and the maze test have it: a report every 5 steps.
symb::evo::FitnessTaskOptions fitness_options() {
  symb::evo::FitnessTaskOptions o;
  o.every = 5;
  return o;
}

symb::evo::OnePlusOneOptions algorithm_options() {
  symb::evo::OnePlusOneOptions o;
  o.sigma_min = kSigmaMin;  // the maze test's settings (tests/sim/evolution_scenario_test.cpp)
  return o;
}

// --- the framework -----------------------------------------------------------------------------

// A framework side: the executor and the session on it (declared in that order: the session goes
// first), and the evolution task when there is one.
struct FrameworkSide {
  symb::kernel::VirtualTimeExecutor executor;
  std::unique_ptr<symb::sim::ScenarioSession> session;
  symb::evo::OnePlusOneTask* evolution = nullptr;
};

// The evolving robot: the bare maze, a fitness task hooked from the IR, a one_plus_one task.
symb::kernel::Status make_evolving(FrameworkSide& side, std::uint64_t seed) {
  symb::sim::SessionOptions options;
  options.seed = seed;
  auto session = symb::sim::ScenarioSession::create(bare_maze(), side.executor, options);
  if (!session) return symb::kernel::Error{session.error()};
  side.session = std::move(session).value();
  symb::os::Node& node = side.session->robot(0).node();
  const auto fitness = node.create("fitness", std::make_unique<symb::evo::FitnessTask>(fitness_options()),
                                   {.priority = 1, .queue_capacity = 8});
  if (!fitness || !node.hook(*node.find("ir"), *fitness)) return symb::kernel::Error{"cannot add the fitness task"};
  symb::evo::OnePlusOneTaskOptions eo;
  eo.algorithm = algorithm_options();
  eo.swap.evaluation = kEvaluation;
  eo.swap.recovery = kRecovery;
  auto made = symb::evo::OnePlusOneTask::create(eo);
  if (!made) return symb::kernel::Error{made.error()};
  side.evolution = made->get();
  if (!node.create("evolution", std::move(made).value(), {.priority = 1, .period = 1s}))
    return symb::kernel::Error{"cannot add the evolution task"};
  return {};
}

// For the breakdown only: the framework driving the maze with one fixed perceptron
// (braitenberg.yaml: ir -> mlp -> wheels), no fitness, no evolution. Its "evaluations" are the
// same virtual time cut into 21 s slices, so it lines up with the two others.
symb::kernel::Status make_fixed(FrameworkSide& side, std::uint64_t seed) {
  auto s = symb::sim::load_scenario(std::string(SYMB_SCENARIO_DIR) + "/braitenberg.yaml");
  if (!s) return symb::kernel::Error{s.error()};
  symb::sim::SessionOptions options;
  options.seed = seed;
  auto session = symb::sim::ScenarioSession::create(*s, side.executor, options);
  if (!session) return symb::kernel::Error{session.error()};
  side.session = std::move(session).value();
  return {};
}

// --- the raw loop ------------------------------------------------------------------------------

class ThymioWithoutIr final : public Enki::Thymio2 {
 public:
  ThymioWithoutIr() { localInteractions.clear(); }
};

class RawEnkiLoop {
 public:
  RawEnkiLoop(const symb::sim::Scenario& scenario, std::uint64_t seed)
      : world_(scenario.world.width, scenario.world.height),
        algorithm_(make_algorithm(seed)),
        noise_(seed, 0x4952),
        enki_random_(seed, 0x454e4b49) {
    std::vector<symb::sim::IrModel::Rect> rects;
    for (const symb::sim::WallSpec& s : scenario.world.walls) {
      const double dx = s.x2 - s.x1, dy = s.y2 - s.y1, length = std::hypot(dx, dy);
      auto* o = new Enki::PhysicalObject;  // owned by world_
      o->setRectangular(length + s.thickness, s.thickness, scenario.world.wall_height, -1);
      o->pos = Enki::Point((s.x1 + s.x2) / 2, (s.y1 + s.y2) / 2);
      o->angle = length > 0 ? std::atan2(dy, dx) : 0.0;
      world_.addObject(o);
      rects.push_back({o->pos.x, o->pos.y, (length + s.thickness) / 2, s.thickness / 2, o->angle});
    }
    const double w = scenario.world.width, h = scenario.world.height, t = 1;
    rects.push_back({w / 2, -t / 2, w / 2 + t, t / 2, 0});
    rects.push_back({w / 2, h + t / 2, w / 2 + t, t / 2, 0});
    rects.push_back({-t / 2, h / 2, t / 2, h / 2 + t, 0});
    rects.push_back({w + t / 2, h / 2, t / 2, h / 2 + t, 0});
    robot_ = new ThymioWithoutIr;  // owned by world_
    const symb::sim::Pose start = scenario.robots.at(0).start;
    robot_->pos = Enki::Point(start.x, start.y);
    robot_->angle = start.theta;
    world_.addObject(robot_);
    ir_model_ = std::make_unique<symb::sim::IrModel>(std::move(rects));
    weights_ = to_float(algorithm_.next());
  }

  // Runs `steps` control periods; every finished evaluation is reported to the algorithm.
  void run(std::int64_t steps) {
    for (std::int64_t k = 0; k < steps; ++k) step();
  }
  const symb::evo::OnePlusOne& algorithm() const { return algorithm_; }

 private:
  static symb::evo::OnePlusOne make_algorithm(std::uint64_t seed) {
    auto a = symb::evo::OnePlusOne::create(algorithm_options(), symb::kernel::RandomStream(seed, 0x4556));
    if (!a) throw std::runtime_error(a.error());
    return std::move(a).value();
  }
  static std::vector<float> to_float(const symb::evo::RealGenome& g) {
    return std::vector<float>(g.values.begin(), g.values.end());
  }

  void step() {
    // Fitness of the command driven since the last reading, then the controller's new command.
    const double f = symb::evo::fitness_step(symb::evo::FitnessFormula::kOnePlusOne, left_, right_, ir_);
    ++step_in_evaluation_;
    if (step_in_evaluation_ > kRecoverySteps) {
      sum_ += f;
      ++counted_;
    }
    if (step_in_evaluation_ >= kRecoverySteps + kEvaluationSteps) {
      algorithm_.report(counted_ == 0 ? 0.0 : sum_ / static_cast<double>(counted_));
      weights_ = to_float(algorithm_.next());
      step_in_evaluation_ = 0;
      sum_ = 0;
      counted_ = 0;
    }
    // The 7-2 tanh perceptron: per output, 7 input weights then the bias.
    double out[2];
    for (std::size_t o = 0; o < 2; ++o) {
      float a = weights_[o * (kIrCount + 1) + kIrCount];
      for (std::size_t i = 0; i < kIrCount; ++i) a += weights_[o * (kIrCount + 1) + i] * (ir_[i] * (1.0f / 4505.0f));
      out[o] = std::clamp(500.0 * std::tanh(static_cast<double>(a)), -500.0, 500.0);
    }
    left_ = out[0];
    right_ = out[1];
    robot_->leftSpeed = left_ / 500.0 * symb::sim::kMaxWheelSpeed;
    robot_->rightSpeed = right_ / 500.0 * symb::sim::kMaxWheelSpeed;
    // Enki's generator from a stream of this loop's own, every step, as EnkiWorld does: what the
    // other sides drew in between changes nothing here.
    Enki::random.setSeed(static_cast<unsigned long>(enki_random_.next_u64()));
    world_.step(kDt, 1);
    pose_[0] = symb::sim::Pose{robot_->pos.x, robot_->pos.y, robot_->angle};
    ir_model_->set_robots(pose_);
    const symb::sim::IrReadings r = ir_model_->read(0, noise_);
    for (std::size_t i = 0; i < kIrCount; ++i) ir_[i] = static_cast<float>(r[i]);
  }

  static constexpr int kRecoverySteps = static_cast<int>(1.0 / kDt);           // 33
  static constexpr int kEvaluationSteps = static_cast<int>(20.0 / kDt + 0.5);  // 667

  Enki::World world_;
  Enki::Thymio2* robot_ = nullptr;
  std::unique_ptr<symb::sim::IrModel> ir_model_;
  symb::evo::OnePlusOne algorithm_;
  std::vector<float> weights_;
  symb::sim::Pose pose_[1];
  float ir_[kIrCount] = {};
  double left_ = 0, right_ = 0;
  int step_in_evaluation_ = 0;
  double sum_ = 0;
  std::uint64_t counted_ = 0;
  symb::kernel::RandomStream noise_;
  symb::kernel::RandomStream enki_random_;
};

// The three sides run slice by slice (kSlice of virtual time each, in a rotating order), each
// side's CPU time summed apart: the box is shared and its speed drifts with the neighbours' load
// over seconds, which whole runs one after the other turned into +-10 % on the ratio.
void BM_Interleaved(benchmark::State& state) {
  const symb::sim::Scenario scenario = bare_maze();
  const auto slices = static_cast<int>(kVirtual / kSlice);
  const auto steps_per_slice =
      static_cast<std::int64_t>(std::llround(std::chrono::duration<double>(kSlice).count() / kDt));
  static std::uint64_t repetition = 0;  // one iteration per repetition: a new seed each
  for (auto _ : state) {
    const std::uint64_t seed = kFirstSeed + repetition++;
    FrameworkSide evolving, fixed;
    for (auto [side, make] : {std::pair{&evolving, &make_evolving}, std::pair{&fixed, &make_fixed}})
      if (auto st = make(*side, seed); !st) {
        state.SkipWithError(st.error().c_str());
        return;
      }
    RawEnkiLoop raw(scenario, seed);
    evolving.session->start();
    fixed.session->start();
    double cpu[3] = {0, 0, 0};  // raw, framework, framework fixed
    for (int k = 0; k < slices; ++k) {
      for (int i = 0; i < 3; ++i) {
        const int which = (k + i) % 3;
        const double c0 = cpu_seconds();
        if (which == 0) raw.run(steps_per_slice);
        if (which == 1) evolving.executor.run_for(kSlice);
        if (which == 2) fixed.executor.run_for(kSlice);
        cpu[which] += cpu_seconds() - c0;
      }
    }
    evolving.session->stop();
    fixed.session->stop();
    const double raw_evaluations = static_cast<double>(raw.algorithm().counts().evaluations);
    const double evaluations = static_cast<double>(evolving.evolution->counts().evaluations);
    const double fixed_slices = std::floor(std::chrono::duration<double>(kVirtual) / (kEvaluation + kRecovery));
    state.SetIterationTime(cpu[0] + cpu[1] + cpu[2]);
    state.counters["raw_evals_per_s"] = raw_evaluations / cpu[0];
    state.counters["evals_per_s"] = evaluations / cpu[1];
    state.counters["fixed_evals_per_s"] = fixed_slices / cpu[2];
    state.counters["ratio"] = (evaluations / cpu[1]) / (raw_evaluations / cpu[0]);
    state.counters["raw_evaluations"] = raw_evaluations;
    state.counters["evaluations"] = evaluations;
    state.counters["raw_champion"] = raw.algorithm().champion_fitness();
    state.counters["champion"] = evolving.evolution->champion_fitness();
  }
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::RegisterBenchmark("BM_Interleaved", &BM_Interleaved)
      ->Iterations(1)
      ->Repetitions(kRepetitions)
      ->UseManualTime()
      ->Unit(benchmark::kMillisecond);
  symb::bench::CollectingReporter reporter(false);
  if (!symb::bench::run_interleaved(argc, argv, reporter)) return 1;
  const char* b = "BM_Interleaved";
  std::printf(
      "\nmaze (1+1)-ONLINE, %.0f min virtual, 1 s recovery + 20 s evaluation, dt 30 ms, one core, the sides "
      "interleaved per %.0f s of virtual time, evaluations per CPU second, medians of %d repetitions\n",
      std::chrono::duration<double>(kVirtual).count() / 60, std::chrono::duration<double>(kSlice).count(),
      kRepetitions);
  std::printf("%-16s %14s %12s %10s\n", "", "evaluations/s", "evaluations", "champion");
  std::printf("%-16s %14.1f %12.0f %10.3f\n", "raw Enki loop", reporter.median(b, "raw_evals_per_s"),
              reporter.median(b, "raw_evaluations"), reporter.median(b, "raw_champion"));
  std::printf("%-16s %14.1f %12.0f %10.3f\n", "framework", reporter.median(b, "evals_per_s"),
              reporter.median(b, "evaluations"), reporter.median(b, "champion"));
  std::printf("%-16s %14.1f   (breakdown: braitenberg.yaml's fixed perceptron, no fitness, no evolution)\n",
              "framework fixed", reporter.median(b, "fixed_evals_per_s"));
  for (const auto& e : reporter.errors()) std::printf("ERROR %s\n", e.c_str());
  const double ratio = reporter.median(b, "ratio");
  const bool met = ratio >= kTarget && reporter.errors().empty();
  std::printf(
      "evolution: the framework at %.0f%% of the raw Enki loop's evaluations per second (median of the "
      "repetitions' ratios, %.0f-%.0f%%; target >= %.0f%%): %s\n",
      100 * ratio, 100 * reporter.lowest(b, "ratio"), 100 * reporter.best(b, "ratio"), 100 * kTarget,
      met ? "MET" : "NOT MET");
  return 0;
}
