// RealGenome's operators (real_genome.hpp): reflection against a bounce-by-bounce reference,
// Gaussian mutation's bounds and spread, the three sigma rules, both crossovers, weights_text read
// back by the network parser, and check().
#include <cmath>
#include <cstddef>
#include <vector>

#include <gtest/gtest.h>

#include "symb/control/network/description.hpp"
#include "symb/evo/genome/real_genome.hpp"
#include "symb/kernel/random_stream.hpp"

namespace symb::evo {
namespace {

// One wall at a time, as a ball would: the reference reflect() must agree with.
double bounce(double v, double lo, double hi) {
  while (v < lo || v > hi) v = v > hi ? 2 * hi - v : 2 * lo - v;
  return v;
}

double variance(const std::vector<double>& x) {
  double mean = 0;
  for (double v : x) mean += v;
  mean /= static_cast<double>(x.size());
  double s = 0;
  for (double v : x) s += (v - mean) * (v - mean);
  return s / static_cast<double>(x.size() - 1);
}

TEST(RealGenomeReflect, InsideIsUnchangedAndBoundsAreFixedPoints) {
  EXPECT_EQ(reflect(0.25, -4, 4), 0.25);
  EXPECT_EQ(reflect(-4, -4, 4), -4);
  EXPECT_EQ(reflect(4, -4, 4), 4);
}

TEST(RealGenomeReflect, OneBounceByHand) {
  EXPECT_DOUBLE_EQ(reflect(4.5, -4, 4), 3.5);
  EXPECT_DOUBLE_EQ(reflect(-5, -4, 4), -3);
  EXPECT_DOUBLE_EQ(reflect(12, -4, 4), -4) << "off the top, all the way across to the bottom";
  EXPECT_DOUBLE_EQ(reflect(20, -4, 4), 4) << "two widths: back at the top";
  EXPECT_DOUBLE_EQ(reflect(1.5, 0, 1), 0.5);
  EXPECT_DOUBLE_EQ(reflect(2.25, 0, 1), 0.25) << "two bounces";
}

TEST(RealGenomeReflect, ManyBouncesAgreeWithTheBounceByBounceReference) {
  kernel::RandomStream random(7);
  for (int i = 0; i < 5000; ++i) {
    const double lo = random.uniform(-10, 5);
    const double hi = lo + random.uniform(0.1, 10);
    const double v = random.uniform(-2000, 2000);  // up to ~40000 bounces at the narrowest
    const double r = reflect(v, lo, hi);
    ASSERT_GE(r, lo);
    ASSERT_LE(r, hi);
    ASSERT_NEAR(r, bounce(v, lo, hi), 1e-9) << "v " << v << " in [" << lo << ", " << hi << "]";
  }
}

TEST(RealGenomeReflect, HugeValuesStayInside) {
  for (double v : {1e300, -1e300, 1.7e308, -1.7e308, 1e17 + 3}) {
    const double r = reflect(v, -4, 4);
    EXPECT_TRUE(std::isfinite(r));
    EXPECT_GE(r, -4);
    EXPECT_LE(r, 4);
  }
  EXPECT_EQ(reflect(8e15 + 1, -4, 4), 1) << "exact folding far out: 8e15 is a whole number of 16-wide periods";
}

TEST(RealGenomeMutation, GenesStayInsideEvenWithTheLargestSigma) {
  kernel::RandomStream random(1);
  RealGenome g = random_real_genome(1000, random, -1, 1, 4);
  g.sigma_max = 4;
  for (int round = 0; round < 50; ++round) {
    mutate_gaussian(g, random);
    for (double v : g.values) ASSERT_TRUE(v >= -1 && v <= 1) << v;
  }
  EXPECT_TRUE(check(g).ok());
}

TEST(RealGenomeMutation, SpreadIsSigmaAwayFromTheBounds) {
  kernel::RandomStream random(2);
  RealGenome g;
  g.lo = -1000;
  g.hi = 1000;
  g.sigma = 0.5;
  g.values.assign(100000, 3.0);
  mutate_gaussian(g, random);
  std::vector<double> d;
  double mean = 0;
  for (double v : g.values) {
    d.push_back(v - 3.0);
    mean += v - 3.0;
  }
  mean /= static_cast<double>(d.size());
  EXPECT_NEAR(mean, 0, 0.01);
  EXPECT_NEAR(variance(d), 0.25, 0.25 * 0.02) << "sample variance within 2% of sigma^2";
}

TEST(RealGenomeMutation, SameSeedSameMutant) {
  kernel::RandomStream r1(9), r2(9);
  RealGenome a = random_real_genome(18, r1);
  RealGenome b = random_real_genome(18, r2);
  mutate_gaussian(a, r1);
  mutate_gaussian(b, r2);
  EXPECT_EQ(a, b);
}

TEST(RealGenomeSigma, OnePlusOneSuccessResetsFailureDoublesUpToMax) {
  RealGenome g;
  g.sigma = 0.7;
  on_success(g);
  EXPECT_EQ(g.sigma, g.sigma_min);
  std::vector<double> seen;
  for (int i = 0; i < 20; ++i) {
    on_failure(g);
    seen.push_back(g.sigma);
  }
  EXPECT_DOUBLE_EQ(seen[0], 2e-4);
  EXPECT_DOUBLE_EQ(seen[1], 4e-4);
  EXPECT_DOUBLE_EQ(seen[13], 1e-4 * 16384);  // 1.6384, still under 4
  EXPECT_DOUBLE_EQ(seen[14], 3.2768);
  EXPECT_EQ(seen[15], 4) << "3.2768 doubled is clamped to sigma_max";
  EXPECT_EQ(seen.back(), 4);
}

TEST(RealGenomeSigma, MedeaChangesWithProbabilityPByEitherFactor) {
  kernel::RandomStream random(3);
  int changed = 0, up = 0;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    RealGenome g;
    g.sigma = 1;
    mutate_sigma_medea(g, random, 0.3);
    if (g.sigma == 1) continue;
    ++changed;
    if (std::abs(g.sigma - 1.35) < 1e-12)
      ++up;
    else
      ASSERT_NEAR(g.sigma, 0.65, 1e-12);
  }
  EXPECT_NEAR(changed / double(n), 0.3, 0.015);
  EXPECT_NEAR(up / double(changed), 0.5, 0.03);

  RealGenome g;
  g.sigma = 3.9;
  for (int i = 0; i < 100; ++i) mutate_sigma_medea(g, random, 1.0);
  EXPECT_GE(g.sigma, g.sigma_min);
  EXPECT_LE(g.sigma, g.sigma_max);
  RealGenome never;
  for (int i = 0; i < 100; ++i) mutate_sigma_medea(never, random, 0.0);
  EXPECT_EQ(never.sigma, 1);
}

TEST(RealGenomeSigma, LogNormalHasTauOneOverRootN) {
  kernel::RandomStream random(4);
  std::vector<double> logs;
  for (int i = 0; i < 20000; ++i) {
    RealGenome g;
    g.values.assign(16, 0.0);  // tau = 1/4
    g.sigma = 0.5;
    mutate_sigma_lognormal(g, random);
    logs.push_back(std::log(g.sigma / 0.5));
  }
  double mean = 0;
  for (double l : logs) mean += l;
  mean /= static_cast<double>(logs.size());
  EXPECT_NEAR(mean, 0, 0.01);
  EXPECT_NEAR(std::sqrt(variance(logs)), 0.25, 0.25 * 0.03);

  RealGenome g;
  g.values.assign(1, 0.0);  // tau = 1: large steps, must stay clamped
  for (int i = 0; i < 1000; ++i) {
    mutate_sigma_lognormal(g, random);
    ASSERT_GE(g.sigma, g.sigma_min);
    ASSERT_LE(g.sigma, g.sigma_max);
  }
}

TEST(RealGenomeCrossover, UniformTakesEachGeneFromOneParent) {
  kernel::RandomStream random(5);
  RealGenome a = random_real_genome(10000, random);
  RealGenome b = random_real_genome(10000, random);
  a.sigma = 0.5;
  b.sigma = 1.5;
  const RealGenome c = crossover_uniform(a, b, random);
  std::size_t from_b = 0;
  for (std::size_t i = 0; i < c.values.size(); ++i) {
    ASSERT_TRUE(c.values[i] == a.values[i] || c.values[i] == b.values[i]);
    from_b += c.values[i] == b.values[i];
  }
  EXPECT_NEAR(from_b / 10000.0, 0.5, 0.02);
  EXPECT_EQ(c.sigma, 1.0);
  EXPECT_TRUE(check(c).ok());

  RealGenome shorter = b;
  shorter.values.pop_back();
  EXPECT_EQ(crossover_uniform(a, shorter, random), a) << "different lengths: a copy of a";
  RealGenome wider = b;
  wider.hi = 5;
  EXPECT_EQ(crossover_uniform(a, wider, random), a) << "different bounds: a copy of a";
}

TEST(RealGenomeCrossover, ArithmeticIsOneBlend) {
  kernel::RandomStream random(6);
  RealGenome a = random_real_genome(50, random);
  RealGenome b = random_real_genome(50, random);
  const RealGenome c = crossover_arithmetic(a, b, random);
  const double w = (c.values[0] - b.values[0]) / (a.values[0] - b.values[0]);
  EXPECT_GE(w, 0);
  EXPECT_LE(w, 1);
  for (std::size_t i = 0; i < c.values.size(); ++i)
    EXPECT_NEAR(c.values[i], w * a.values[i] + (1 - w) * b.values[i], 1e-9);
  EXPECT_TRUE(check(c).ok());
  RealGenome other = b;
  other.values.push_back(0);
  EXPECT_EQ(crossover_arithmetic(a, other, random), a);
}

TEST(RealGenomeText, WeightsTextReadsBackToTheSameFloats) {
  kernel::RandomStream random(8);
  RealGenome g = random_real_genome(200, random);
  g.values.push_back(-4);
  g.values.push_back(1e-30);
  g.values.push_back(0);
  const std::string text = weights_text(g);
  auto parsed = control::network::parse_numbers(text);
  ASSERT_TRUE(parsed.ok()) << parsed.error();
  ASSERT_EQ(parsed->size(), g.values.size());
  for (std::size_t i = 0; i < g.values.size(); ++i) EXPECT_EQ((*parsed)[i], static_cast<float>(g.values[i])) << i;
  EXPECT_EQ(weights_text(RealGenome{}), "");
  RealGenome wide;
  wide.lo = -1e300;
  wide.hi = 1e300;
  wide.values = {1e300, -1e40, 0.5};
  EXPECT_EQ(weights_text(wide), "3.4028235e+38 -3.4028235e+38 0.5") << "beyond float range: the largest float";
}

TEST(RealGenomeCheck, AcceptsValidRefusesEachBreach) {
  kernel::RandomStream random(10);
  const RealGenome good = random_real_genome(18, random);
  EXPECT_TRUE(check(good).ok());
  EXPECT_EQ(good.values.size(), 18u);

  auto refused = [](RealGenome g, const char* what) {
    auto s = check(g);
    EXPECT_FALSE(s.ok()) << what;
    return s.ok() ? std::string() : s.error();
  };
  RealGenome g = good;
  g.values[3] = 4.5;
  EXPECT_EQ(refused(g, "outside"), "value 3: 4.5 outside [-4, 4]");
  g = good;
  g.values[0] = std::nan("");
  EXPECT_EQ(refused(g, "nan"), "value 0: not finite");
  g = good;
  g.lo = 4;
  EXPECT_NE(refused(g, "lo == hi").find("bounds"), std::string::npos);
  g = good;
  g.hi = INFINITY;
  EXPECT_NE(refused(g, "infinite hi").find("bounds"), std::string::npos);
  g = good;
  g.sigma = 5;
  EXPECT_NE(refused(g, "sigma > max").find("sigma"), std::string::npos);
  g = good;
  g.sigma_min = 0;
  EXPECT_NE(refused(g, "min 0").find("sigma"), std::string::npos);
  g = good;
  g.sigma = 1e-5;
  EXPECT_NE(refused(g, "sigma < min").find("sigma"), std::string::npos);
}

}  // namespace
}  // namespace symb::evo
