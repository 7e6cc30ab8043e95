// Encapsulated (mu+1)-ONLINE: the pure state machine (mu_plus_one.hpp) on toy fitness functions
// (it improves a noisy sphere; the population fills with mu random members first; re-evaluations
// happen with probability rho and average or replace as chosen; a child replaces the worst member
// only when strictly better; same stream, same run) and the mu_plus_one task in a node with a
// scripted sensor: it replaces the controller TASK per candidate and improves a fitness it can
// only reach through the controllers it evolves.
#include "symb/evo/mu_plus_one/mu_plus_one.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "symb/control/control_task_types.hpp"
#include "symb/evo/evo_task_types.hpp"
#include "symb/evo/mu_plus_one/mu_plus_one_task.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"

namespace symb::evo {
namespace {

using namespace std::chrono_literals;

double mu_sphere(const RealGenome& g) {
  double s = 0;
  for (double v : g.values) s += (v - 1) * (v - 1);
  return -s;  // higher is better; best at all genes = 1
}

MuPlusOne make_mu(MuPlusOneOptions o = {}, std::uint64_t seed = 7) {
  auto a = MuPlusOne::create(o, kernel::RandomStream(seed));
  EXPECT_TRUE(a.ok()) << (a ? "" : a.error());
  return std::move(a).value();
}

// Measured (seeds 1..3, 3000 evaluations, noise sd 0.5, mu 10, sigma 0.3): the best member's true
// fitness -63/-57/-76 (the best of the random start) -> -0.91/-0.66/-0.63.
TEST(MuPlusOne, ImprovesOnANoisySphere) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE(seed);
    MuPlusOneOptions o;
    o.sigma = 0.3;
    MuPlusOne a = make_mu(o, seed);
    kernel::RandomStream noise(seed + 100);
    for (std::size_t k = 0; k < o.mu; ++k) a.report(mu_sphere(a.next()) + 0.5 * noise.normal());
    const double start = mu_sphere(a.best().genome);
    for (int k = 0; k < 3000; ++k) a.report(mu_sphere(a.next()) + 0.5 * noise.normal());
    const double end = mu_sphere(a.best().genome);
    std::printf("seed %llu: best member %.2f -> %.2f\n", static_cast<unsigned long long>(seed), start, end);
    EXPECT_GT(end, 0.1 * start);  // fitness is negative
    EXPECT_GT(end, -5.0);
    EXPECT_EQ(a.population().size(), o.mu);
    for (const Member& m : a.population())
      for (double v : m.genome.values) {
        EXPECT_GE(v, -4.0);
        EXPECT_LE(v, 4.0);
      }
  }
}

TEST(MuPlusOne, FirstMuEvaluationsFillThePopulationWithRandomGenomes) {
  MuPlusOneOptions o;
  o.mu = 6;
  MuPlusOne a = make_mu(o);
  std::set<std::vector<double>> seen;
  for (std::size_t k = 0; k < o.mu; ++k) {
    EXPECT_EQ(a.candidate_kind(), MuCandidate::kInitial);
    EXPECT_EQ(a.candidate_index(), k);
    seen.insert(a.next().values);
    a.report(static_cast<double>(k));
    EXPECT_EQ(a.population().size(), k + 1);
  }
  EXPECT_EQ(seen.size(), o.mu) << "mu different random genomes";
  EXPECT_NE(a.candidate_kind(), MuCandidate::kInitial);
  EXPECT_EQ(a.best().fitness, 5.0);
  EXPECT_DOUBLE_EQ(a.mean_fitness(), 2.5);
  EXPECT_EQ(a.counts().initial, o.mu);
}

// Pure-noise fitness, 20000 steps: re-evaluations come with probability rho; an averaged member's
// fitness is the mean of all its measurements; a child enters exactly when it beats the worst.
TEST(MuPlusOne, ReevaluationRateAveragingAndReplacementAsSpecified) {
  MuPlusOneOptions o;
  o.rho = 0.3;
  MuPlusOne a = make_mu(o, 11);
  kernel::RandomStream noise(99);
  std::uint64_t reevaluations = 0, children = 0, replacements = 0;
  for (int k = 0; k < 20000; ++k) {
    const MuCandidate kind = a.candidate_kind();
    const std::vector<Member> before = a.population();
    const RealGenome candidate = a.next();
    const std::size_t index = a.candidate_index();
    const double f = noise.uniform();
    a.report(f);
    if (kind == MuCandidate::kReevaluation) {
      ++reevaluations;
      ASSERT_EQ(candidate, before[index].genome) << "a member itself is run again";
      const Member& m = a.population()[index];
      EXPECT_EQ(m.measurements, before[index].measurements + 1);
      const double n = static_cast<double>(m.measurements);
      EXPECT_NEAR(m.fitness, (before[index].fitness * (n - 1) + f) / n, 1e-12);
    } else if (kind == MuCandidate::kChild) {
      ++children;
      const auto worst = std::min_element(before.begin(), before.end(),
                                          [](const Member& x, const Member& y) { return x.fitness < y.fitness; });
      const std::size_t w = static_cast<std::size_t>(worst - before.begin());
      if (f > worst->fitness) {
        ++replacements;
        EXPECT_EQ(a.population()[w].genome, candidate);
        EXPECT_EQ(a.population()[w].fitness, f);
        EXPECT_EQ(a.population()[w].measurements, 1u);
      } else {
        for (std::size_t i = 0; i < before.size(); ++i) EXPECT_EQ(a.population()[i].genome, before[i].genome);
      }
    }
  }
  const double share = static_cast<double>(reevaluations) / static_cast<double>(reevaluations + children);
  EXPECT_NEAR(share, 0.3, 0.015) << reevaluations << " re-evaluations";
  EXPECT_EQ(a.counts().reevaluations, reevaluations);
  EXPECT_EQ(a.counts().children, children);
  EXPECT_EQ(a.counts().replacements, replacements);
  EXPECT_GT(replacements, 100u);
  const double crossover_share = static_cast<double>(a.counts().crossovers) / static_cast<double>(children);
  EXPECT_NEAR(crossover_share, o.crossover, 0.02);
}

TEST(MuPlusOne, ReplaceModeKeepsOnlyTheNewestMeasurement) {
  MuPlusOneOptions o;
  o.rho = 0.5;
  o.reevaluation = Reevaluation::kReplace;
  MuPlusOne a = make_mu(o, 3);
  kernel::RandomStream noise(5);
  std::uint64_t checked = 0;
  for (int k = 0; k < 2000; ++k) {
    const MuCandidate kind = a.candidate_kind();
    const std::size_t index = a.candidate_index();
    const double f = noise.uniform();
    a.report(f);
    if (kind == MuCandidate::kReevaluation) {
      EXPECT_EQ(a.population()[index].fitness, f);
      ++checked;
    }
  }
  EXPECT_GT(checked, 500u);
}

TEST(MuPlusOne, ChildIsAParentMutatedWithSigma) {
  MuPlusOneOptions o;
  o.sigma = 0.01;
  o.crossover = 0;
  o.rho = 0;
  o.selection = ParentSelection::kUniform;
  MuPlusOne a = make_mu(o, 5);
  for (std::size_t k = 0; k < o.mu; ++k) a.report(0.0);
  ASSERT_EQ(a.candidate_kind(), MuCandidate::kChild);
  const RealGenome& parent = a.population()[a.candidate_index()].genome;
  double largest = 0;
  for (std::size_t k = 0; k < o.genes; ++k)
    largest = std::max(largest, std::abs(a.next().values[k] - parent.values[k]));
  EXPECT_GT(largest, 0.0);
  EXPECT_LT(largest, 0.06);  // 6 sigma
}

TEST(MuPlusOne, SameStreamSameRun) {
  MuPlusOne a = make_mu({}, 3), b = make_mu({}, 3), c = make_mu({}, 4);
  for (int k = 0; k < 500; ++k) {
    a.report(mu_sphere(a.next()));
    b.report(mu_sphere(b.next()));
    c.report(mu_sphere(c.next()));
  }
  EXPECT_EQ(a.best().genome, b.best().genome);
  EXPECT_EQ(a.best().fitness, b.best().fitness);
  EXPECT_EQ(a.counts().reevaluations, b.counts().reevaluations);
  EXPECT_NE(a.best().genome, c.best().genome);
}

TEST(MuPlusOne, BadOptionsAndNanFitness) {
  const auto bad = [](auto change) {
    MuPlusOneOptions o;
    change(o);
    return !MuPlusOne::create(o, kernel::RandomStream(1)).ok();
  };
  EXPECT_TRUE(bad([](MuPlusOneOptions& o) { o.mu = 1; }));
  EXPECT_TRUE(bad([](MuPlusOneOptions& o) { o.rho = 1; }));
  EXPECT_TRUE(bad([](MuPlusOneOptions& o) { o.rho = std::nan(""); }));
  EXPECT_TRUE(bad([](MuPlusOneOptions& o) { o.sigma = 0; }));
  EXPECT_TRUE(bad([](MuPlusOneOptions& o) { o.crossover = 1.5; }));
  EXPECT_TRUE(bad([](MuPlusOneOptions& o) { o.genes = 0; }));
  EXPECT_TRUE(bad([](MuPlusOneOptions& o) { o.lo = 5; }));
  MuPlusOneOptions o;
  o.mu = 2;
  o.rho = 0;
  MuPlusOne a = make_mu(o);
  a.report(std::nan(""));  // the worst fitness, not a NaN that nothing beats
  a.report(1.0);
  a.report(-1e9);  // a child better than the NaN member replaces it
  EXPECT_EQ(a.counts().replacements, 1u);
  for (const Member& m : a.population()) EXPECT_TRUE(std::isfinite(m.fitness));
}

// --- the task ----------------------------------------------------------------------------------

// A sensor that sends 7 IR readings every 30 ms: all zero (open space).
class MuOpenSpace : public os::Task {
 protected:
  void on_tick() override { send(0, {0, 0, 0, 0, 0, 0, 0}); }
};

class MuCountingWheels : public os::Task {
 public:
  std::set<os::TaskId> senders() const {
    std::lock_guard lock(mu_);
    return senders_;
  }

 protected:
  void on_message(const os::Message& m) override {
    std::lock_guard lock(mu_);
    senders_.insert(m.source);
  }

 private:
  mutable std::mutex mu_;
  std::set<os::TaskId> senders_;
};

struct MuRig {
  kernel::VirtualTimeExecutor ex;
  os::TaskTypeRegistry registry;
  std::unique_ptr<os::Node> node;
  MuCountingWheels* wheels = nullptr;
  kernel::Result<os::TaskId> evo = kernel::Error{"not made"};

  explicit MuRig(std::string_view evo_params, std::uint64_t seed = 1) {
    EXPECT_TRUE(control::register_control_task_types(registry, {}).ok());
    EXPECT_TRUE(register_evo_task_types(registry, {}).ok());
    node = std::make_unique<os::Node>(ex, os::NodeConfig{.name = "bot", .seed = seed, .types = &registry});
    const auto ir = *node->create("ir", std::make_unique<MuOpenSpace>(), {.priority = 3, .period = 30ms});
    auto w = std::make_unique<MuCountingWheels>();
    wheels = w.get();
    (void)*node->create("wheels", std::move(w), {.queue_capacity = 8});
    auto f = node->create("fitness", "fitness", std::vector<os::ParamAssignment>{{"formula", "one_plus_one", 1}});
    EXPECT_TRUE(f.ok());
    EXPECT_TRUE(node->hook(ir, *f).ok());
    auto a = os::parse_param_assignments(evo_params);
    EXPECT_TRUE(a.ok());
    evo = node->create("mu_plus_one", "evolution", *a);
  }
};

struct MuProbes {
  std::mutex mu;
  std::vector<float> best, mean, evaluations;
};

TEST(MuPlusOneTask, ReplacesTheControllerTaskAndImprovesInOpenSpace) {
  MuRig rig("mu=6 sigma=0.5 evaluation=300ms recovery=60ms");
  ASSERT_TRUE(rig.evo.ok()) << rig.evo.error();
  auto probes = std::make_shared<MuProbes>();
  rig.node->set_probe_sink([probes](const os::ProbeSample& s) {
    std::lock_guard lock(probes->mu);
    if (s.channel == "best_fitness") probes->best.push_back(s.values[0]);
    if (s.channel == "mean_fitness") probes->mean.push_back(s.values[0]);
    if (s.channel == "evaluations") probes->evaluations.push_back(s.values[0]);
  });
  std::set<os::TaskId> controllers;
  const std::size_t hooks_at_start = rig.node->hooks().size();
  for (int k = 0; k < 150; ++k) {
    rig.ex.run_for(360ms);
    const auto c = rig.node->find("controller");
    ASSERT_TRUE(c.has_value()) << "a candidate is always running";
    controllers.insert(*c);
    EXPECT_EQ(rig.node->info(*c)->type, "mlp");
  }
  EXPECT_EQ(rig.node->task_count(), 5u) << "ir, wheels, fitness, evolution, one controller";
  EXPECT_EQ(rig.node->hooks().size(), hooks_at_start + 4) << "fitness -> evolution, the candidate's three";
  EXPECT_GT(controllers.size(), 140u) << "a new task per candidate, not new weights";
  EXPECT_GT(rig.wheels->senders().size(), 140u);
  std::lock_guard lock(probes->mu);
  ASSERT_GT(probes->evaluations.size(), 140u);
  EXPECT_EQ(probes->evaluations.back(), static_cast<float>(probes->evaluations.size()));
  // In open space the best perceptron drives straight at full speed (fitness -> 1).
  const float mean_after_init = probes->mean[5];
  std::printf("open space: best %.3f -> %.3f, mean %.3f -> %.3f\n", probes->best[5], probes->best.back(),
              mean_after_init, probes->mean.back());
  EXPECT_GT(probes->mean.back(), mean_after_init + 0.2f);
  EXPECT_GT(probes->best.back(), 0.8f);
}

TEST(MuPlusOneTask, SameNodeSeedSameEvolution) {
  auto run = [](std::uint64_t seed) {
    MuRig rig("mu=4 evaluation=300ms recovery=60ms", seed);
    EXPECT_TRUE(rig.evo.ok());
    auto trace = std::make_shared<std::vector<float>>();
    rig.node->set_probe_sink([trace](const os::ProbeSample& s) {
      if (s.channel == "fitness") trace->push_back(s.values[0]);
    });
    rig.ex.run_for(10s);
    return *trace;
  };
  const auto a = run(1), b = run(1), c = run(2);
  ASSERT_GT(a.size(), 20u);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
}

TEST(MuPlusOneTask, RecoveryIsNotCountedAndEveryEvaluationIsRecorded) {
  kernel::VirtualTimeExecutor ex;
  os::TaskTypeRegistry registry;
  ASSERT_TRUE(control::register_control_task_types(registry, {}).ok());
  ASSERT_TRUE(register_evo_task_types(registry, {}).ok());
  os::Node node(ex, os::NodeConfig{.name = "bot", .seed = 3, .types = &registry});
  const auto ir = *node.create("ir", std::make_unique<MuOpenSpace>(), {.priority = 3, .period = 30ms});
  (void)*node.create("wheels", std::make_unique<MuCountingWheels>(), {.queue_capacity = 8});
  auto f = node.create("fitness", "fitness", std::vector<os::ParamAssignment>{});
  ASSERT_TRUE(f.ok());
  ASSERT_TRUE(node.hook(ir, *f).ok());
  MuPlusOneTaskOptions o;
  o.algorithm.mu = 3;
  o.algorithm.rho = 0.5;
  o.swap.evaluation = 600ms;
  o.swap.recovery = 300ms;
  auto made = MuPlusOneTask::create(o);
  ASSERT_TRUE(made.ok()) << made.error();
  MuPlusOneTask* task = made->get();
  ASSERT_TRUE(node.create("evolution", std::move(made).value(), {.priority = 1, .period = 1s}).ok());
  ex.run_for(30s);
  EXPECT_EQ(task->state(), EvolutionState::kRunning) << task->error();
  const auto h = task->history();
  ASSERT_GT(h.size(), 25u);  // 30 s / 0.9 s
  EXPECT_EQ(h.size(), task->counts().evaluations);
  EXPECT_EQ(task->controllers_created(), h.size() + 1);
  for (const MuEvaluationRecord& r : h) {
    // 600 ms of 30 ms steps counted (20 or 21), the 10 recovery steps not.
    EXPECT_GE(r.steps, 19u);
    EXPECT_LE(r.steps, 22u);
  }
  EXPECT_EQ(h[0].kind, MuCandidate::kInitial);
  EXPECT_EQ(task->population().size(), 3u);
  EXPECT_GT(task->counts().reevaluations, 3u);
  ASSERT_TRUE(task->best().has_value());
  EXPECT_EQ(task->best()->fitness, h.back().best_fitness);
}

TEST(MuPlusOneTask, RegistryRejectsBadParametersWithAReason) {
  const auto error = [](std::string_view params) {
    MuRig rig(params);
    return rig.evo ? std::string() : rig.evo.error();
  };
  EXPECT_NE(error("selection=best").find("selection"), std::string::npos);
  EXPECT_NE(error("reevaluation=sometimes").find("reevaluation"), std::string::npos);
  EXPECT_NE(error("genes=18").find("genes"), std::string::npos);
  EXPECT_NE(error("mu=1").find("mu"), std::string::npos);
  EXPECT_NE(error("lo=3 hi=2").find("bounds"), std::string::npos);
  EXPECT_NE(error("sensor=\"a b\"").find("cannot name"), std::string::npos);
  EXPECT_EQ(error("mu=4 rho=0.1 sigma=0.2 crossover=0 selection=uniform reevaluation=replace"), "");
}

TEST(MuPlusOneTask, WaitsForAMissingFitnessTask) {
  kernel::VirtualTimeExecutor ex;
  os::TaskTypeRegistry registry;
  ASSERT_TRUE(control::register_control_task_types(registry, {}).ok());
  ASSERT_TRUE(register_evo_task_types(registry, {}).ok());
  os::Node node(ex, os::NodeConfig{.name = "bot", .seed = 3, .types = &registry});
  const auto ir = *node.create("ir", std::make_unique<MuOpenSpace>(), {.priority = 3, .period = 30ms});
  (void)*node.create("wheels", std::make_unique<MuCountingWheels>(), {.queue_capacity = 8});
  auto made = MuPlusOneTask::create({});
  ASSERT_TRUE(made.ok());
  MuPlusOneTask* task = made->get();
  ASSERT_TRUE(node.create("evolution", std::move(made).value(), {.priority = 1, .period = 1s}).ok());
  ex.run_for(3s);
  EXPECT_EQ(task->state(), EvolutionState::kWaiting);
  EXPECT_FALSE(node.find("controller").has_value());
  auto f = node.create("fitness", "fitness", std::vector<os::ParamAssignment>{});
  ASSERT_TRUE(f.ok());
  ASSERT_TRUE(node.hook(ir, *f).ok());
  ex.run_for(2s);
  EXPECT_EQ(task->state(), EvolutionState::kRunning);
  EXPECT_TRUE(node.find("controller").has_value());
}

}  // namespace
}  // namespace symb::evo
