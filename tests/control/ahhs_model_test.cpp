// The AHHS model against hand-computed steps, the four pitfalls of the authors' 2009 reference
// code (docs/ahhs.md: one test each), bounds over a million steps of random networks, and
// conservation of hormone under diffusion alone.
#include <cmath>

#include <gtest/gtest.h>

#include "symb/control/ahhs/model.hpp"
#include "symb/control/ahhs/mutation.hpp"
#include "symb/control/ahhs/parser.hpp"
#include "symb/kernel/random_stream.hpp"

namespace symb::control::ahhs {
namespace {

Model must(std::string_view text) {
  auto n = parse_network(text);
  EXPECT_TRUE(n.ok()) << (n ? "" : n.error());
  auto m = Model::create(n ? *n : Network{});
  EXPECT_TRUE(m.ok()) << (m ? "" : m.error());
  return std::move(m).value();
}

TEST(AhhsModel, OneStepByHand) {
  Model m = must(R"(compartments 1
hormone a base 0.1 decay 0.5 diffusion 0 start 0.4
hormone b base 0 decay 0 diffusion 0 start 0.5
sensor 0 in 0
actuator 0 in 0
rule sensor 0 -> a centre 1 width 1 fixed 0.5 dependent 1
rule nonlinear a -> b centre 0.5 width 0.5 fixed 0 dependent 2
rule actuator b -> 0 centre 0.5 width 1 fixed 0.25 dependent 1
)");
  const float s[] = {0.5f};
  m.step(s);
  // a: 0.4 + 0.1 - 0.5 * 0.4 + tau(0.5; 1, 1) * (1 * 0.5 + 0.5) = 0.3 + 0.5 * 1 = 0.8
  EXPECT_FLOAT_EQ(m.levels(0)[0], 0.8f);
  // b: 0.5 + tau(a = 0.4; 0.5, 0.5) * (2 * 0.4 * 0.5) = 0.5 + 0.8 * 0.4 = 0.82
  EXPECT_FLOAT_EQ(m.levels(0)[1], 0.82f);
  // actuator from b at the start of the step (0.5): tau = 1, 0.5 + 0.25
  EXPECT_FLOAT_EQ(m.actuators()[0], 0.75f);
  m.step(s);
  EXPECT_FLOAT_EQ(m.levels(0)[0], 1.0f) << "clamped to max";
  EXPECT_LE(m.actuators()[0], 1.0f) << "actuators clamped to [-1, 1]";
}

// Pitfall 1: in the reference code's direct path a linear hormone rule changed its *source*
// hormone; the published intent (and its lookup-table path) is that source regulates target.
TEST(AhhsModel, Pitfall1LinearHormoneRuleRegulatesItsTarget) {
  Model m = must(R"(compartments 1
hormone src base 0 decay 0 diffusion 0 start 0.5
hormone dst base 0 decay 0 diffusion 0 start 0
rule hormone src -> dst centre 0.5 width 1 fixed 0.1
)");
  m.step({});
  EXPECT_FLOAT_EQ(m.levels(0)[0], 0.5f) << "the source is left alone";
  EXPECT_FLOAT_EQ(m.levels(0)[1], 0.1f) << "the target gets the dose";
}

// Pitfall 2: the reference diffusion loop used its loop counter as the neighbour's id, so with
// more than two compartments hormone flowed between compartments that are not neighbours.
TEST(AhhsModel, Pitfall2DiffusionOnlyBetweenLinkedNeighbours) {
  Model m = must(R"(compartments 3
link 1 2
link 2 0
hormone h base 0 decay 0 diffusion 0.25
)");
  // chain 1 - 2 - 0: compartment 1 is not a neighbour of 0
  m.levels(1)[0] = 1.0f;
  m.step({});
  EXPECT_FLOAT_EQ(m.levels(1)[0], 0.75f);
  EXPECT_FLOAT_EQ(m.levels(2)[0], 0.25f);
  EXPECT_FLOAT_EQ(m.levels(0)[0], 0.0f) << "no flow between compartments 1 and 0";
  m.step({});
  EXPECT_GT(m.levels(0)[0], 0.0f) << "it arrives through compartment 2, one step later";
}

// Pitfall 3: the reference hormone mutation drew rand() % 2 with base emission as case 2, so base
// emission never mutated. Here each of the three numbers is drawn a third of the time.
TEST(AhhsModel, Pitfall3MutationReachesBaseEmission) {
  auto n = parse_network("compartments 2; link 0 1; hormone h base 0.1 decay 0.1 diffusion 0.1");
  ASSERT_TRUE(n.ok()) << n.error();
  kernel::RandomStream random(7);
  int counts[3] = {0, 0, 0};
  Network net = *n;
  for (int k = 0; k < 3000; ++k) ++counts[static_cast<int>(mutate_hormone(net, 0, random, 0.05))];
  for (int c : counts) EXPECT_NEAR(c, 1000, 150);
  EXPECT_NE(net.hormones[0].base, 0.1f);
  EXPECT_TRUE(validate(net).ok());
  // The whole-network operator too, and its results stay valid.
  Network other = *n;
  for (int k = 0; k < 200; ++k) {
    mutate(other, random);
    ASSERT_TRUE(validate(other).ok()) << validate(other).error();
  }
  EXPECT_NE(other.hormones[0].base, 0.1f);
}

// Pitfall 4: the reference trigger used a strict '<', so a value exactly on the window's edge
// gave 0. The window is continuous (0 on the edge either way), so the edge is harmless; what is
// not is a width of 0, which would never fire: it is rejected with its location.
TEST(AhhsModel, Pitfall4TriggerWindowEdgesAndZeroWidth) {
  EXPECT_FLOAT_EQ(trigger(0.5f, 0.5f, 0.25f), 1.0f);
  EXPECT_FLOAT_EQ(trigger(0.75f, 0.5f, 0.25f), 0.0f);
  EXPECT_FLOAT_EQ(trigger(0.25f, 0.5f, 0.25f), 0.0f);
  EXPECT_FLOAT_EQ(trigger(0.625f, 0.5f, 0.25f), 0.5f);
  EXPECT_GT(trigger(std::nextafter(0.75f, 0.0f), 0.5f, 0.25f), 0.0f);
  EXPECT_FLOAT_EQ(trigger(2.0f, 0.5f, 0.25f), 0.0f);
  auto bad = parse_network("compartments 1\nhormone h\nrule hormone h -> h centre 0 width 0");
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().rfind("3:36: width must be above 0", 0), 0u) << bad.error();
}

Network random_network(kernel::RandomStream& r) {
  Network n;
  n.compartments = 1 + static_cast<std::uint32_t>(r.below(6));
  for (std::uint32_t c = 1; c < n.compartments; ++c) n.links.push_back({c - 1, c});
  if (n.compartments > 3) n.links.push_back({0, n.compartments - 1});
  const std::size_t nh = 1 + r.below(6);
  for (std::size_t h = 0; h < nh; ++h) {
    Hormone x;
    x.name = "h" + std::to_string(h);
    x.base = static_cast<float>(r.uniform(0, 0.1));
    x.decay = static_cast<float>(r.uniform(0, 0.1));
    x.diffusion = static_cast<float>(r.uniform(0, 0.5));
    x.min = static_cast<float>(r.uniform(-1, 0));
    x.max = static_cast<float>(r.uniform(0.5, 2));
    x.start = x.min;
    n.hormones.push_back(x);
  }
  for (std::uint32_t s = 0; s < 4; ++s) n.sensors.push_back({s, static_cast<std::uint32_t>(r.below(n.compartments))});
  for (std::uint32_t a = 0; a < 2; ++a) n.actuators.push_back({a, static_cast<std::uint32_t>(r.below(n.compartments))});
  const std::size_t nr = 20;
  for (std::size_t k = 0; k < nr; ++k) {
    Rule x;
    x.kind = static_cast<RuleKind>(r.below(4));
    x.source = static_cast<std::uint32_t>(x.kind == RuleKind::kSensor ? r.below(4) : r.below(nh));
    x.target = static_cast<std::uint32_t>(x.kind == RuleKind::kActuator ? r.below(2) : r.below(nh));
    // The authors' initialisation ranges, with a large dose now and then to hit the bounds.
    x.centre = static_cast<float>(r.uniform(-2, 2));
    x.width = static_cast<float>(r.uniform(0.01, 1));
    x.fixed = static_cast<float>(r.uniform(-0.2, 0.2));
    x.dependent = static_cast<float>(r.uniform(-2, 2) * (r.below(4) == 0 ? 50 : 1));
    n.rules.push_back(x);
  }
  return n;
}

TEST(AhhsModel, LevelsStayWithinBoundsOverAMillionStepsOfRandomNetworks) {
  kernel::RandomStream r(2024);
#ifdef SYMB_SANITIZER
  // Ten networks for a tenth of the steps each: the sanitizers look for memory errors and
  // undefined behaviour, which every step runs the same code for; the bounds over a long run are
  // a numerical claim, the release build's to check.
  constexpr int kNetworks = 10, kSteps = 10'000;
#else
  constexpr int kNetworks = 10, kSteps = 100'000;  // 10^6 steps in all
#endif
  for (int k = 0; k < kNetworks; ++k) {
    auto m = Model::create(random_network(r));
    ASSERT_TRUE(m.ok()) << m.error();
    float sensors[4];
    bool ok = true;
    for (int t = 0; t < kSteps && ok; ++t) {
      for (float& s : sensors) s = static_cast<float>(r.uniform());
      m.value().step(sensors);
      for (std::uint32_t c = 0; c < m->compartments(); ++c)
        for (std::size_t h = 0; h < m->hormones(); ++h) {
          const float x = m->levels(c)[h];
          const Hormone& spec = m->network().hormones[h];
          ok = ok && std::isfinite(x) && x >= spec.min && x <= spec.max;
        }
      for (float a : m->actuators()) ok = ok && a >= -1.0f && a <= 1.0f;
      ASSERT_TRUE(ok) << "network " << k << " step " << t;
    }
  }
}

TEST(AhhsModel, DiffusionAloneConservesEveryHormone) {
  // A 6 x 6 grid, three hormones with different diffusion rates; nothing else.
  Network n;
  n.compartments = 36;
  for (std::uint32_t y = 0; y < 6; ++y)
    for (std::uint32_t x = 0; x < 6; ++x) {
      if (x + 1 < 6) n.links.push_back({y * 6 + x, y * 6 + x + 1});
      if (y + 1 < 6) n.links.push_back({y * 6 + x, (y + 1) * 6 + x});
    }
  for (float d : {0.25f, 0.1f, 0.01f}) n.hormones.push_back({"", 0, 0, d, 0, 1, 0});
  auto m = Model::create(n);
  ASSERT_TRUE(m.ok()) << m.error();
  kernel::RandomStream r(5);
  for (std::uint32_t c = 0; c < 36; ++c)
    for (std::size_t h = 0; h < 3; ++h) m.value().levels(c)[h] = static_cast<float>(r.uniform());
  const double before[3] = {m->total(0), m->total(1), m->total(2)};
  for (int t = 0; t < 5000; ++t) m.value().step({});
  for (std::size_t h = 0; h < 3; ++h) EXPECT_NEAR(m->total(h), before[h], 1e-4 * 36) << "hormone " << h;
  // ... and it did spread: the fastest hormone is nearly even now.
  float lo = 1, hi = 0;
  for (std::uint32_t c = 0; c < 36; ++c) {
    lo = std::min(lo, m->levels(c)[0]);
    hi = std::max(hi, m->levels(c)[0]);
  }
  EXPECT_LT(hi - lo, 1e-3f);
}

TEST(AhhsModel, ValidateRejectsWhatCannotRun) {
  Network n;
  n.compartments = 3;
  n.links = {{0, 1}, {1, 2}};
  n.hormones = {{"h", 0, 0, 0.6f, 0, 1, 0}};
  auto st = validate(n);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().find("exceeds 1"), std::string::npos) << st.error();
  n.hormones[0].diffusion = 0.5f;
  EXPECT_TRUE(validate(n).ok()) << validate(n).error();
  n.links.push_back({1, 0});
  EXPECT_FALSE(validate(n).ok());
}

}  // namespace
}  // namespace symb::control::ahhs
