// Island migrants (apps/evolve/islands.hpp) in both evolution algorithms: for (mu+1) a migrant is
// the next candidate once the population is full, evaluated as a child, and enters the population
// only by the algorithm's own rule (replacing the worst member when strictly better); for (1+1) a
// migrant that beats the champion is counted taken. Same migrants at the same steps, same run.
#include <algorithm>
#include <vector>

#include <gtest/gtest.h>

#include "symb/evo/mu_plus_one/mu_plus_one.hpp"
#include "symb/evo/one_plus_one/one_plus_one.hpp"

namespace symb::evo {
namespace {

MuPlusOne make_mu(std::uint64_t seed) {
  MuPlusOneOptions o;
  o.mu = 4;
  o.genes = 3;
  auto a = MuPlusOne::create(o, kernel::RandomStream(seed));
  EXPECT_TRUE(a.ok());
  return std::move(a).value();
}

RealGenome migrant(double first, double rest) {
  RealGenome g;
  g.values = {first, rest, rest};
  return g;
}

double worst(const MuPlusOne& a) {
  double w = a.population().front().fitness;
  for (const Member& m : a.population()) w = std::min(w, m.fitness);
  return w;
}

TEST(IslandMigrant, MuPlusOneEvaluatesAMigrantAsAChildThatReplacesTheWorstOnlyIfBetter) {
  MuPlusOne a = make_mu(3);
  a.report(1.0);
  a.immigrate(migrant(99, 0.5));  // while the population fills: it waits
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(a.candidate_kind(), MuCandidate::kInitial);
    a.report(2.0 + k);  // the population: fitness 1 to 4
  }
  // Full now: the migrant is the candidate, put into the bounds, with the fixed sigma.
  ASSERT_EQ(a.candidate_kind(), MuCandidate::kChild);
  EXPECT_EQ(a.next().values, (std::vector<double>{4.0, 0.5, 0.5}));
  EXPECT_EQ(a.next().sigma, a.options().sigma);
  EXPECT_EQ(a.counts().immigrants, 1u);
  const std::vector<Member> before = a.population();
  a.report(0.5);  // worse than the worst (1.0): lost, as any child
  EXPECT_EQ(a.counts().immigrants_taken, 0u);
  EXPECT_EQ(a.population().size(), before.size());
  for (std::size_t i = 0; i < before.size(); ++i) EXPECT_EQ(a.population()[i].genome.values, before[i].genome.values);
  EXPECT_NE(a.next().values, (std::vector<double>{4.0, 0.5, 0.5}));  // back to its own candidates

  // The candidate under evaluation is not disturbed; the migrant comes next and wins a place.
  const RealGenome current = a.next();
  a.immigrate(migrant(0.25, 0.25));
  EXPECT_EQ(a.next().values, current.values);
  a.report(worst(a) - 1);  // the current candidate: no place
  ASSERT_EQ(a.next().values, (std::vector<double>{0.25, 0.25, 0.25}));
  const double lowest = worst(a);
  a.report(lowest + 10);
  EXPECT_EQ(a.counts().immigrants, 2u);
  EXPECT_EQ(a.counts().immigrants_taken, 1u);
  EXPECT_GE(worst(a), lowest);
  EXPECT_TRUE(std::any_of(a.population().begin(), a.population().end(), [](const Member& m) {
    return m.genome.values == std::vector<double>{0.25, 0.25, 0.25};
  }));
}

TEST(IslandMigrant, TheSameMigrantsAtTheSameStepsGiveTheSameRun) {
  MuPlusOne a = make_mu(9), b = make_mu(9);
  for (int k = 0; k < 200; ++k) {
    if (k % 25 == 10) {
      a.immigrate(migrant(0.1 * k / 25, -1));
      b.immigrate(migrant(0.1 * k / 25, -1));
    }
    ASSERT_EQ(a.next().values, b.next().values) << k;
    const double f = -std::abs(a.next().values[0] - 1) + 0.01 * k;
    a.report(f);
    b.report(f);
  }
  EXPECT_GT(a.counts().immigrants, 0u);
  EXPECT_EQ(a.counts().immigrants, b.counts().immigrants);
  EXPECT_EQ(a.counts().immigrants_taken, b.counts().immigrants_taken);
}

TEST(IslandMigrant, OnePlusOneCountsAMigrantThatBecomesChampionAsTaken) {
  auto made = OnePlusOne::create({}, kernel::RandomStream(5));
  ASSERT_TRUE(made.ok());
  OnePlusOne a = std::move(made).value();
  RealGenome g = a.next();
  std::fill(g.values.begin(), g.values.end(), 0.5);
  a.report(1.0);
  a.immigrate(g);
  a.report(0.0);  // the challenger drawn before the migrant came: fails
  while (a.candidate_kind() != Candidate::kChallenger) a.report(1.0);
  ASSERT_EQ(a.next().values, g.values);
  a.report(2.0);  // beats the champion's 1.0
  EXPECT_EQ(a.counts().immigrants, 1u);
  EXPECT_EQ(a.counts().immigrants_taken, 1u);
  EXPECT_EQ(a.champion().values, g.values);
}

}  // namespace
}  // namespace symb::evo
