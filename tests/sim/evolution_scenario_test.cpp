// (1+1)-ONLINE evolution on the simulated Thymio in the maze (issue 7, "must show"): the maze of
// scenarios/maze.yaml with its controller removed; a `fitness` task (Nolfi's per-step fitness,
// formula one_plus_one) hooked from the IR sensor and an evolution task (one_plus_one) on the
// robot's own node, which replaces the controller TASK by a new 7-2 tanh perceptron per candidate.
// After a budget of virtual time the champion is replayed for 10 minutes in a fresh maze and its
// mean per-step fitness (measured by the same fitness task) is compared with the hand-written
// Braitenberg perceptron's (scenarios/network/braitenberg.w), measured the same way.
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "symb/evo/fitness/fitness_task.hpp"
#include "symb/evo/one_plus_one/one_plus_one_task.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/sim/scenario_session.hpp"

#include "support/maze_evolution.hpp"
#include "support/measured.hpp"
#include "support/tsan_skip.hpp"

namespace symb::sim {
namespace {

// The seeds of the evolution test (every one in release; the sanitizer builds check the same
// code for memory errors and races on one seed: 10-20x slower).
#ifdef SYMB_SANITIZER
constexpr std::uint64_t kEvolutionSeeds = 1;
#else
constexpr std::uint64_t kEvolutionSeeds = 5;
#endif

using namespace std::chrono_literals;

using maze_test::add_fitness;
using maze_test::bare_maze;
using maze_test::maze_with_perceptron;
using maze_test::Replay;
using maze_test::replay;
using test::load_shipped;

// The fitness task reports every 5 steps (150 ms), as scenarios/evolve_maze.yaml has it: a
// candidate's window starts and ends up to 4 steps late, for a fifth of the messages.
constexpr std::uint32_t kFitnessEvery = 5;

struct Evolved {
  evo::RealGenome champion;
  double champion_fitness = 0;
  std::uint64_t evaluations = 0, successes = 0, contact_steps = 0;
};

Evolved evolve(std::uint64_t seed, kernel::Duration budget, const evo::OnePlusOneTaskOptions& evolution_options) {
  kernel::VirtualTimeExecutor executor;
  SessionOptions options;
  options.seed = seed;
  auto session = ScenarioSession::create(bare_maze(), executor, options);
  EXPECT_TRUE(session.ok()) << (session ? "" : session.error());
  if (!session) return {};
  os::Node& node = (*session)->robot(0).node();
  add_fitness(node, kFitnessEvery);
  auto made = evo::OnePlusOneTask::create(evolution_options);
  EXPECT_TRUE(made.ok());
  evo::OnePlusOneTask* evolution = made->get();
  EXPECT_TRUE(node.create("evolution", std::move(made).value(), {.priority = 1, .period = 1s}).ok());
  (*session)->start();
  executor.run_for(budget);
  (*session)->stop();
  EXPECT_EQ(evolution->state(), evo::EvolutionState::kRunning) << evolution->error();
  Evolved e;
  if (auto c = evolution->champion()) e.champion = *c;
  e.champion_fitness = evolution->champion_fitness();
  e.evaluations = evolution->counts().evaluations;
  e.successes = evolution->counts().successes;
  e.contact_steps = (*session)->world().state(0).contact_steps;
  return e;
}

// The run's parameters: the reference's (controller-models.md 6.1: sigma_0 = 1, sigma_max = 4,
// p = 0.2, genes in [-4, 4], 1 s recovery) except two, sigma_min and the evaluation time, which
// the reference's robot world had tuned for its own setting. With sigma_min = 1e-4 and 10 s the
// rule crawls by steps of 1e-4 and the maze's noise decides (measured, 4 h budget, seeds 1..8:
// 0-103% of Braitenberg, 2 of 8 with contacts; docs/evolution.md). With sigma_min = 0.05 and 20 s
// evaluations (tau is "the most influential parameter", 6.2):
//   120 min budget, seeds 1..12: 95-163% of Braitenberg; 11 of 12 without a contact in the replay
//   (seed 6: 95%, 4499 contact steps); seeds 1..5 (fitness reported every 5 steps): 148, 161, 134,
//   154, 158%, no contact (kMeasuredPercent, docs/evolution.md).
//   60 min budget, seeds 1..12: 8 of 12 at >= 80%.
// The whole test (5 x 2 h of evolution, 6 replays of 10 min) takes about 3.5 s in release.
evo::OnePlusOneTaskOptions run_options() {
  evo::OnePlusOneTaskOptions o;
  o.algorithm.sigma_min = 0.05;
  o.swap.evaluation = 20s;
  o.swap.recovery = 1s;
  return o;
}
constexpr kernel::Duration kBudget = 120min;

// Each seed's replay as a share of Braitenberg's fitness, measured (release; docs/evolution.md's
// table quotes these). A seed's run is deterministic (same seed, same champion), so each is held
// to its own figure within 10 points either way: the spread over seeds (95-163% for 12 seeds)
// would hide a loss that one fixed seed shows. Ten points is a tenth of Braitenberg's fitness:
// a loss that size on any seed fails. (The release build, g++, and the ASan build, clang, measure
// the same figures.)
constexpr double kMeasuredPercent[] = {148, 161, 134, 154, 158};
constexpr double kMarginPoints = 10;
// The Braitenberg perceptron's own replay, measured: fitness 0.4653 (0.465 in docs/evolution.md).
constexpr double kBraitenbergFitness = 0.4653;

TEST(EvolutionScenario, OnePlusOneOnlineReachesBraitenbergInTheMazeWithFiveSeeds) {
  SYMB_SKIP_UNDER_TSAN();
  const Replay baseline = replay(maze_with_perceptron("network/braitenberg.w"), 10min);
  std::printf("braitenberg: fitness %.4f, %llu contact steps, %.0f cm\n", baseline.fitness,
              static_cast<unsigned long long>(baseline.contact_steps), baseline.distance);
  ASSERT_TRUE(testing::near_measured(baseline.fitness, kBraitenbergFitness, 0.005));
  EXPECT_EQ(baseline.contact_steps, 0u);
  for (std::uint64_t seed = 1; seed <= kEvolutionSeeds; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const Evolved e = evolve(seed, kBudget, run_options());
    EXPECT_GT(e.evaluations, 300u);  // 120 min / 21 s = 342
    const Replay r = replay(maze_with_perceptron(evo::weights_text(e.champion)), 10min);
    std::printf(
        "seed %llu: %llu evaluations, %llu successes, champion %.4f; replay fitness %.4f (%.0f%% of "
        "braitenberg), %llu contact steps, %.0f cm\n",
        static_cast<unsigned long long>(seed), static_cast<unsigned long long>(e.evaluations),
        static_cast<unsigned long long>(e.successes), e.champion_fitness, r.fitness, 100 * r.fitness / baseline.fitness,
        static_cast<unsigned long long>(r.contact_steps), r.distance);
    EXPECT_TRUE(testing::near_measured(100 * r.fitness / baseline.fitness, kMeasuredPercent[seed - 1], kMarginPoints));
    EXPECT_EQ(r.contact_steps, 0u);
  }
}

TEST(EvolutionScenario, SameSeedSameChampion) {
  const Evolved a = evolve(3, 10min, run_options()), b = evolve(3, 10min, run_options());
  const Evolved c = evolve(4, 10min, run_options());
  EXPECT_EQ(a.champion, b.champion);
  EXPECT_EQ(a.champion_fitness, b.champion_fitness);
  EXPECT_NE(a.champion, c.champion);
}

}  // namespace
}  // namespace symb::sim
