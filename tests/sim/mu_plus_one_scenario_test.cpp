// Encapsulated (mu+1)-ONLINE on the simulated Thymio in the maze (issue 7, deliverable 3b): the
// maze of scenarios/maze.yaml with its controller removed; a `fitness` task (Nolfi's per-step
// fitness, formula one_plus_one) hooked from the IR sensor and a mu_plus_one task on the robot's
// own node, which replaces the controller TASK by a new 7-2 tanh perceptron per candidate. After a
// budget of virtual time the population's best member is replayed for 10 minutes in a fresh maze
// and its mean per-step fitness (the same fitness task) is compared with the hand-written
// Braitenberg perceptron's (scenarios/network/braitenberg.w), measured the same way. The setup is
// tests/sim/evolution_scenario_test.cpp's, with the algorithm swapped.
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "symb/evo/fitness/fitness_task.hpp"
#include "symb/evo/mu_plus_one/mu_plus_one_task.hpp"
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
constexpr std::uint64_t kMuSeeds = 1;
#else
constexpr std::uint64_t kMuSeeds = 3;
#endif

using namespace std::chrono_literals;

using maze_test::add_fitness;
using maze_test::bare_maze;
using maze_test::maze_with_perceptron;
using maze_test::Replay;
using maze_test::replay;
using test::load_shipped;

struct MuEvolved {
  evo::Member best;
  double mean_fitness = 0;
  evo::MuPlusOneCounts counts;
};

MuEvolved evolve_mu(std::uint64_t seed, kernel::Duration budget, const evo::MuPlusOneTaskOptions& evolution_options) {
  kernel::VirtualTimeExecutor executor;
  SessionOptions options;
  options.seed = seed;
  auto session = ScenarioSession::create(bare_maze(), executor, options);
  EXPECT_TRUE(session.ok()) << (session ? "" : session.error());
  if (!session) return {};
  os::Node& node = (*session)->robot(0).node();
  add_fitness(node);
  auto made = evo::MuPlusOneTask::create(evolution_options);
  EXPECT_TRUE(made.ok()) << (made ? "" : made.error());
  if (!made) return {};
  evo::MuPlusOneTask* evolution = made->get();
  EXPECT_TRUE(node.create("evolution", std::move(made).value(), {.priority = 1, .period = 1s}).ok());
  (*session)->start();
  executor.run_for(budget);
  (*session)->stop();
  EXPECT_EQ(evolution->state(), evo::EvolutionState::kRunning) << evolution->error();
  MuEvolved e;
  if (auto b = evolution->best()) e.best = *b;
  const auto h = evolution->history();
  if (!h.empty()) e.mean_fitness = h.back().mean_fitness;
  e.counts = evolution->counts();
  return e;
}

// The run's parameters, chosen by measurement (docs/evolution.md "(mu+1)-ONLINE"): mu = 10,
// rho = 0.2, sigma = 0.5 (fixed), uniform crossover with p = 0.5, binary tournament, averaged
// re-evaluation, tau = 20 s counted after 1 s of recovery, genes in [-4, 4]. Replay of the best
// member (highest stored fitness), seeds 1..12, percent of Braitenberg (contact steps):
//   240 min: 169 163 167 174 127(4287) 166 150 167 90(15463) 83(188) 164 79(537): 11 of 12 at
//            >= 80 %, 8 of 12 without a contact. The test runs seeds 1..3 (all 0 contacts).
//   120 min: 9 of 12 at >= 80 %, 7 of 12 without a contact (seed 3: 27 contact steps).
//   Others at 120 min, 12 seeds: mu 10 sigma 0.5 rho 0.3: 10 >= 80 %, 7 without contact; mu 14
//   sigma 0.7: 10 and 7; tau 30 s: 9 and 5; mu 6 sigma 0.5 (8 seeds): 7 and 3.
// A failure is mostly a member scored once (lucky) in a spot of the maze that favours a gliding
// wall-follower: the replay in the full maze then touches walls. The (1+1) run with its tuned
// sigma_min does better at this budget (11 of 12, tests/sim/evolution_scenario_test.cpp).
evo::MuPlusOneTaskOptions mu_run_options() {
  evo::MuPlusOneTaskOptions o;
  o.algorithm.mu = 10;
  o.algorithm.rho = 0.2;
  o.algorithm.sigma = 0.5;
  o.algorithm.crossover = 0.5;
  o.swap.evaluation = 20s;
  o.swap.recovery = 1s;
  return o;
}
constexpr kernel::Duration kMuBudget = 240min;

// Each seed's replay as a share of Braitenberg's fitness, measured (release; the bold figures of
// docs/evolution.md's (mu+1) table). A seed's run is deterministic (same seed, same best), so each
// is held to its own figure within 10 points either way: the spread over 12 seeds (79-174%) would
// hide a loss that one fixed seed shows. Ten points is a tenth of Braitenberg's fitness: a
// loss that size on any seed fails. (The release build, g++, and the ASan build, clang, measure the
// same figures.)
constexpr double kMuMeasuredPercent[] = {169, 163, 167};
constexpr double kMuMarginPoints = 10;
constexpr double kMuBraitenbergFitness = 0.4653;  // measured; 0.465 in docs/evolution.md

TEST(MuPlusOneScenario, ReachesBraitenbergInTheMazeWithThreeSeedsIn4Hours) {
  SYMB_SKIP_UNDER_TSAN();
  const Replay baseline = replay(maze_with_perceptron("network/braitenberg.w"), 10min);
  std::printf("braitenberg: fitness %.4f, %llu contact steps, %.0f cm\n", baseline.fitness,
              static_cast<unsigned long long>(baseline.contact_steps), baseline.distance);
  ASSERT_TRUE(testing::near_measured(baseline.fitness, kMuBraitenbergFitness, 0.005));
  for (std::uint64_t seed = 1; seed <= kMuSeeds; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const MuEvolved e = evolve_mu(seed, kMuBudget, mu_run_options());
    EXPECT_GT(e.counts.evaluations, 650u);   // 240 min / 21 s = 685
    EXPECT_GT(e.counts.reevaluations, 90u);  // rho 0.2 of 675
    const Replay r = replay(maze_with_perceptron(evo::weights_text(e.best.genome)), 10min);
    std::printf(
        "seed %llu: %llu evaluations (%llu re-evaluations, %llu replacements), best %.4f (%llu runs), population "
        "mean %.4f; replay fitness %.4f (%.0f%% of braitenberg), %llu contact steps, %.0f cm\n",
        static_cast<unsigned long long>(seed), static_cast<unsigned long long>(e.counts.evaluations),
        static_cast<unsigned long long>(e.counts.reevaluations), static_cast<unsigned long long>(e.counts.replacements),
        e.best.fitness, static_cast<unsigned long long>(e.best.measurements), e.mean_fitness, r.fitness,
        100 * r.fitness / baseline.fitness, static_cast<unsigned long long>(r.contact_steps), r.distance);
    EXPECT_TRUE(
        testing::near_measured(100 * r.fitness / baseline.fitness, kMuMeasuredPercent[seed - 1], kMuMarginPoints));
    EXPECT_EQ(r.contact_steps, 0u);
  }
}

TEST(MuPlusOneScenario, SameSeedSameBest) {
  const MuEvolved a = evolve_mu(3, 10min, mu_run_options()), b = evolve_mu(3, 10min, mu_run_options());
  const MuEvolved c = evolve_mu(4, 10min, mu_run_options());
  EXPECT_EQ(a.best.genome, b.best.genome);
  EXPECT_EQ(a.best.fitness, b.best.fitness);
  EXPECT_NE(a.best.genome, c.best.genome);
}

}  // namespace
}  // namespace symb::sim
