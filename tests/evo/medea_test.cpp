// mEDEA's pure algorithm (evo/medea.hpp): the list of received genomes (one per sender, latest),
// the uniform pick, the emptied list, the inactive state, the sigma rule, malformed input.
#include "symb/evo/medea/medea.hpp"

#include <array>
#include <chrono>
#include <cmath>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "symb/control/control_task_types.hpp"
#include "symb/evo/evo_task_types.hpp"
#include "symb/evo/genome/genome.hpp"
#include "symb/evo/medea/medea_task.hpp"
#include "symb/io/bytes.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"

namespace symb::evo {
namespace {

MedeaOptions small(std::size_t genes = 4) {
  MedeaOptions o;
  o.genes = genes;
  o.sigma = 0.1;
  return o;
}

Medea make_medea(MedeaOptions o = small(), std::uint64_t seed = 1) {
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
  const Medea m = make_medea();
  EXPECT_TRUE(m.active());
  ASSERT_EQ(m.genome().values.size(), 4u);
  for (double v : m.genome().values) {
    EXPECT_GE(v, -4);
    EXPECT_LE(v, 4);
  }
  EXPECT_EQ(m.genome().sigma, 0.1);
  EXPECT_NE(make_medea(small(), 1).genome(), make_medea(small(), 2).genome());
  EXPECT_EQ(make_medea(small(), 3).genome(), make_medea(small(), 3).genome());
}

TEST(Medea, InactiveForALifetimeWhenNothingWasHeardThenActiveAgain) {
  Medea m = make_medea();
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
  Medea m = make_medea();
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
  Medea m = make_medea(o, 5);
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
  Medea m = make_medea(o, 9);
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
  Medea m = make_medea(o, 11);
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
  Medea m = make_medea();
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

TEST(Medea, RefusesMoreSendersThanItKeeps) {
  Medea m = make_medea();
  for (std::uint64_t s = 0; s < kMaxMedeaSenders; ++s) ASSERT_TRUE(m.receive(s, constant(0)).ok());
  EXPECT_FALSE(m.receive(kMaxMedeaSenders, constant(0)).ok());
  EXPECT_TRUE(m.receive(0, constant(1)).ok());  // a known sender is still updated
  EXPECT_EQ(m.received_count(), kMaxMedeaSenders);
  EXPECT_EQ(m.counts().malformed, 1u);
}

TEST(Medea, ReceivesGenomeTextsAndReusesARepeatedOne) {
  Medea m = make_medea();
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

// --- the task ----------------------------------------------------------------------------------

using namespace std::chrono_literals;

// A sensor that sends 7 IR readings every 30 ms: all zero (open space).
class MedeaOpenSpace : public os::Task {
 protected:
  void on_tick() override { send(0, {0, 0, 0, 0, 0, 0, 0}); }
};

// Counts the wheel commands.
class MedeaWheels : public os::Task {
 public:
  std::uint64_t commands() const {
    std::lock_guard lock(mu_);
    return commands_;
  }

 protected:
  void on_message(const os::Message&) override {
    std::lock_guard lock(mu_);
    ++commands_;
  }

 private:
  mutable std::mutex mu_;
  std::uint64_t commands_ = 0;
};

// A radio as sim::RadioTask behaves, without a medium: keeps what hooked tasks send it (the
// broadcasts) and sends on what is posted to it (what it "received").
class FakeRadio : public os::Task {
 public:
  std::vector<std::string> sent() const {
    std::lock_guard lock(mu_);
    return sent_;
  }

 protected:
  void on_message(const os::Message& m) override {
    if (!m.source.valid()) {
      send(0, m.payload);
      return;
    }
    std::lock_guard lock(mu_);
    if (const io::Bytes* b = io::bytes_of(m)) sent_.emplace_back(b->text());
  }

 private:
  mutable std::mutex mu_;
  std::vector<std::string> sent_;
};

TEST(MedeaTask, BroadcastsRunsGoesInactiveAndComesBackWhenItHearsAGenome) {
  kernel::VirtualTimeExecutor ex;
  os::TaskTypeRegistry registry;
  ASSERT_TRUE(control::register_control_task_types(registry, {}).ok());
  ASSERT_TRUE(register_evo_task_types(registry, {}).ok());
  os::Node node(ex, os::NodeConfig{.name = "bot", .seed = 3, .types = &registry});
  (void)*node.create("ir", std::make_unique<MedeaOpenSpace>(), {.priority = 3, .period = 30ms});
  auto w = std::make_unique<MedeaWheels>();
  MedeaWheels* wheels = w.get();
  (void)*node.create("wheels", std::move(w), {.queue_capacity = 8});
  auto r = std::make_unique<FakeRadio>();
  FakeRadio* radio = r.get();
  const os::TaskId radio_id = *node.create("radio", std::move(r), {.priority = 2, .queue_capacity = 64});
  MedeaTaskOptions o;
  o.lifetime = 3s;
  auto made = MedeaTask::create(o);
  ASSERT_TRUE(made.ok()) << made.error();
  MedeaTask* medea = made->get();
  ASSERT_TRUE(
      node.create("medea", std::move(made).value(), {.priority = 1, .period = 300ms, .queue_capacity = 64}).ok());
  auto hear = [&](float sender, const std::string& text) {
    os::Message m;
    m.payload = os::Payload{sender};
    m.payload.blob = std::make_shared<const io::Bytes>(text);
    EXPECT_TRUE(node.post(radio_id, m).ok());
  };

  // Lifetime 1 (0-3 s): its random genome drives; it is broadcast at once and every 300 ms.
  ex.run_for(2900ms);
  EXPECT_EQ(medea->state(), EvolutionState::kRunning) << medea->error();
  EXPECT_TRUE(medea->active());
  EXPECT_TRUE(node.find("controller").has_value());
  EXPECT_GT(wheels->commands(), 80u);
  const std::vector<std::string> sent = radio->sent();
  ASSERT_GE(sent.size(), 9u);
  auto first = parse_genome_text(sent.front());
  ASSERT_TRUE(first.ok()) << first.error();
  EXPECT_EQ(std::get<RealGenome>(*first), medea->genome());
  EXPECT_EQ(sent.back(), sent.front());  // the same genome all lifetime long

  // Nothing heard: lifetime 2 is inactive: no controller, no broadcast, no wheel command.
  ex.run_for(400ms);
  EXPECT_FALSE(medea->active());
  EXPECT_FALSE(node.find("controller").has_value());
  const std::size_t broadcasts = radio->sent().size();
  const std::uint64_t commands = wheels->commands();
  ex.run_for(1s);
  EXPECT_EQ(radio->sent().size(), broadcasts);
  EXPECT_EQ(wheels->commands(), commands);

  // It keeps listening: a malformed text is counted and ignored, a good genome is kept.
  hear(4, "genome real\nvalues 1 2 oops");
  RealGenome heard;
  heard.values.assign(16, 2.5);
  heard.sigma = 0.01;
  hear(7, to_text(Genome{heard}));
  ex.run_for(100ms);
  EXPECT_EQ(medea->counts().malformed, 1u);
  EXPECT_EQ(medea->counts().received, 1u);
  ex.run_for(2s);  // lifetime 3 starts at 6 s with the heard genome, mutated
  EXPECT_TRUE(medea->active());
  EXPECT_TRUE(node.find("controller").has_value());
  for (double v : medea->genome().values) EXPECT_NEAR(v, 2.5, 0.1);
  EXPECT_GT(radio->sent().size(), broadcasts);
  EXPECT_EQ(medea->controllers_created(), 2u);
  EXPECT_EQ(medea->counts().lifetimes, 2u);
  EXPECT_EQ(medea->counts().inactive_lifetimes, 1u);
}

TEST(MedeaTask, TypeIsRegisteredAndChecksItsParameters) {
  os::TaskTypeRegistry registry;
  ASSERT_TRUE(control::register_control_task_types(registry, {}).ok());
  ASSERT_TRUE(register_evo_task_types(registry, {}).ok());
  kernel::VirtualTimeExecutor ex;
  os::Node node(ex, os::NodeConfig{.name = "bot", .types = &registry});
  for (std::string_view params : {"sigma=8", "lo=4 hi=-4", "activation=relu", "layers=\"0\"", "radio=\"two words\"",
                                  "sigma_probability=2", "lifetime=0s"}) {
    auto a = os::parse_param_assignments(params);
    ASSERT_TRUE(a.ok()) << params;
    EXPECT_FALSE(node.create("medea", "medea", *a).ok()) << params;
  }
  auto ok = os::parse_param_assignments("inputs=5 layers=\"3 2\" lifetime=20s sigma=0.1 sigma_probability=0.5");
  ASSERT_TRUE(ok.ok());
  EXPECT_TRUE(node.create("medea", "medea", *ok).ok());
}

}  // namespace
}  // namespace symb::evo
