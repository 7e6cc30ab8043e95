// mEDEA's pure algorithm (evo/medea.hpp): the list of received genomes (one per sender, latest),
// the uniform pick, the emptied list, the inactive state, the sigma rule, malformed input.
#include "symb/evo/medea.hpp"

#include <array>
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "symb/evo/genome.hpp"

namespace symb::evo {
namespace {

MedeaOptions small(std::size_t genes = 4) {
  MedeaOptions o;
  o.genes = genes;
  o.sigma = 0.1;
  return o;
}

Medea make(MedeaOptions o = small(), std::uint64_t seed = 1) {
  auto m = Medea::create(o, kernel::RandomStream(seed, 0));
  EXPECT_TRUE(m.ok()) << (m ? "" : m.error());
  return std::move(m).value();
}

// A genome whose genes are all `v` (sigma as given), the bounds of the default options.
RealGenome constant(double v, std::size_t genes = 4, double sigma = 0.1) {
  RealGenome g;
  g.values.assign(genes, v);
  g.sigma = sigma;
  g.sigma_min = 0.001;
  g.sigma_max = 4;
  return g;
}

TEST(Medea, RejectsBadOptions) {
  MedeaOptions o = small();
  o.genes = 0;
  EXPECT_FALSE(Medea::create(o, kernel::RandomStream(1, 0)).ok());
  o = small();
  o.lo = 5;
  EXPECT_FALSE(Medea::create(o, kernel::RandomStream(1, 0)).ok());
  o = small();
  o.sigma = 10;  // above sigma_max
  EXPECT_FALSE(Medea::create(o, kernel::RandomStream(1, 0)).ok());
  o = small();
  o.sigma_probability = 1.5;
  EXPECT_FALSE(Medea::create(o, kernel::RandomStream(1, 0)).ok());
}

TEST(Medea, StartsActiveWithARandomGenomeInTheBounds) {
  const Medea m = make();
  EXPECT_TRUE(m.active());
  ASSERT_EQ(m.genome().values.size(), 4u);
  for (double v : m.genome().values) {
    EXPECT_GE(v, -4);
    EXPECT_LE(v, 4);
  }
  EXPECT_EQ(m.genome().sigma, 0.1);
  EXPECT_NE(make(small(), 1).genome(), make(small(), 2).genome());
  EXPECT_EQ(make(small(), 3).genome(), make(small(), 3).genome());
}

TEST(Medea, InactiveForALifetimeWhenNothingWasHeardThenActiveAgain) {
  Medea m = make();
  m.end_of_lifetime();
  EXPECT_FALSE(m.active());
  EXPECT_EQ(m.counts().inactive_lifetimes, 1u);
  m.end_of_lifetime();  // still nothing heard
  EXPECT_FALSE(m.active());
  ASSERT_TRUE(m.receive(7, constant(1)).ok());  // listening while inactive
  m.end_of_lifetime();
  EXPECT_TRUE(m.active());
  EXPECT_EQ(m.counts().lifetimes, 3u);
  EXPECT_EQ(m.counts().active_lifetimes, 1u);
  EXPECT_EQ(m.counts().inactive_lifetimes, 2u);
}

TEST(Medea, KeepsTheLatestGenomePerSenderAndEmptiesTheListAtTheEndOfALifetime) {
  Medea m = make();
  ASSERT_TRUE(m.receive(1, constant(1)).ok());
  ASSERT_TRUE(m.receive(1, constant(2)).ok());  // replaces sender 1's
  EXPECT_EQ(m.received_count(), 1u);
  m.end_of_lifetime();
  EXPECT_EQ(m.received_count(), 0u);
  // The pick is sender 1's latest genome plus small noise (sigma 0.1).
  for (double v : m.genome().values) EXPECT_NEAR(v, 2, 0.6);
  m.end_of_lifetime();  // the list was emptied: nothing to pick
  EXPECT_FALSE(m.active());
}

TEST(Medea, PicksUniformlyAmongTheSenders) {
  // Four senders with genes 0, 1, 2, 3 (far apart next to sigma 0.01): 4000 picks.
  MedeaOptions o = small(2);
  o.sigma = 0.01;
  Medea m = make(o, 5);
  std::array<int, 4> picked{};
  const int kPicks = 4000;
  for (int i = 0; i < kPicks; ++i) {
    for (int s = 0; s < 4; ++s) ASSERT_TRUE(m.receive(static_cast<std::uint64_t>(s), constant(s, 2, 0.01)).ok());
    m.end_of_lifetime();
    const long k = std::lround(m.genome().values[0]);
    ASSERT_GE(k, 0);
    ASSERT_LT(k, 4);
    ++picked[static_cast<std::size_t>(k)];
  }
  // Expected 1000 each; binomial sd ~27: +-150 is > 5 sd.
  for (int c : picked) EXPECT_NEAR(c, kPicks / 4, 150) << c;
}

TEST(Medea, MutatesWithTheGenomesOwnSigma) {
  // The picked genome's sigma (not the options') sets the noise: mean |noise| = sigma sqrt(2/pi).
  MedeaOptions o = small(1000);
  Medea m = make(o, 9);
  for (double sigma : {0.01, 1.0}) {
    ASSERT_TRUE(m.receive(1, constant(0, 1000, sigma)).ok());
    m.end_of_lifetime();
    double sum = 0;
    for (double v : m.genome().values) sum += std::fabs(v);
    EXPECT_NEAR(sum / 1000, sigma * std::sqrt(2 / M_PI), 0.1 * sigma);
    EXPECT_EQ(m.genome().sigma, sigma);  // sigma_probability 0: sigma travels unchanged
  }
}

TEST(Medea, SigmaRuleMultipliesByOnePlusOrMinusFactorWithItsProbability) {
  MedeaOptions o = small();
  o.sigma_probability = 1;
  Medea m = make(o, 11);
  int up = 0, down = 0;
  for (int i = 0; i < 400; ++i) {
    ASSERT_TRUE(m.receive(1, constant(0, 4, 0.1)).ok());
    m.end_of_lifetime();
    const double s = m.genome().sigma;
    if (std::fabs(s - 0.135) < 1e-12) ++up;
    if (std::fabs(s - 0.065) < 1e-12) ++down;
  }
  EXPECT_EQ(up + down, 400);
  EXPECT_NEAR(up, 200, 50);
  // Clamped into [sigma_min, sigma_max].
  ASSERT_TRUE(m.receive(1, constant(0, 4, 4)).ok());
  for (int i = 0; i < 20; ++i) {
    m.end_of_lifetime();
    EXPECT_LE(m.genome().sigma, 4);
    EXPECT_GE(m.genome().sigma, 0.001);
    ASSERT_TRUE(m.receive(1, m.genome()).ok());
  }
}

TEST(Medea, CountsAndIgnoresMalformedGenomes) {
  Medea m = make();
  EXPECT_FALSE(m.receive(1, constant(0, 5)).ok());  // wrong length
  RealGenome other = constant(0);
  other.lo = -8;
  other.hi = 8;
  EXPECT_FALSE(m.receive(1, other).ok());  // other bounds
  RealGenome bad = constant(0);
  bad.values[0] = std::nan("");
  EXPECT_FALSE(m.receive(1, bad).ok());
  EXPECT_FALSE(m.receive_text(2, "genome real\nvalues 1 2 x").ok());
  EXPECT_FALSE(m.receive_text(2, "").ok());
  EXPECT_FALSE(m.receive_text(2, std::string("\0\xff\x01", 3)).ok());
  EXPECT_EQ(m.counts().malformed, 6u);
  EXPECT_EQ(m.received_count(), 0u);
  m.end_of_lifetime();
  EXPECT_FALSE(m.active());
}

TEST(Medea, ReceivesGenomeTextsAndReusesARepeatedOne) {
  Medea m = make();
  const std::string text = to_text(Genome{constant(0.5)});
  ASSERT_TRUE(m.receive_text(3, text).ok());
  ASSERT_TRUE(m.receive_text(3, text).ok());
  EXPECT_EQ(m.received_count(), 1u);
  EXPECT_EQ(m.counts().received, 2u);
  m.end_of_lifetime();
  EXPECT_TRUE(m.active());
  for (double v : m.genome().values) EXPECT_NEAR(v, 0.5, 0.6);
  // Heard again in the next lifetime (cached text): back in the list.
  ASSERT_TRUE(m.receive_text(3, text).ok());
  EXPECT_EQ(m.received_count(), 1u);
}

}  // namespace
}  // namespace symb::evo
