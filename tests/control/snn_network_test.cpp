// SpikingNetwork (spiking_network.hpp): bit-identical to a naive per-neuron loop over
// step_neuron() with a list of pending pulses, synaptic delays to the millisecond, the spec round
// trip, reset, and create()'s checks.
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "symb/control/snn/spiking_network.hpp"
#include "symb/kernel/random_stream.hpp"

namespace {

using namespace symb;
using namespace symb::control::snn;

NetworkSpec random_spec(std::uint64_t seed, std::size_t n, std::size_t per_neuron, Integration scheme) {
  kernel::RandomStream r(seed);
  NetworkSpec spec;
  spec.integration = scheme;
  for (std::size_t i = 0; i < n; ++i) {
    spec.neurons.push_back(params_of(static_cast<NeuronClass>(r.below(kNeuronClassCount))));
    spec.bias.push_back(static_cast<float>(r.uniform(0, 4)));
  }
  // Synapses in random order of sources: the network keeps spec order within a row.
  for (std::size_t k = 0; k < n * per_neuron; ++k) {
    Synapse s;
    s.source = static_cast<std::uint32_t>(r.below(n));
    s.target = static_cast<std::uint32_t>(r.below(n));
    s.weight = static_cast<float>(r.uniform() < 0.8 ? r.uniform(0, 6) : -r.uniform(0, 10));
    s.delay = static_cast<std::uint32_t>(r.below(kMaxDelay + 1));
    spec.synapses.push_back(s);
  }
  return spec;
}

// The straightforward implementation: one NeuronState per neuron, step_neuron(), and a list of
// pending pulses in the order they were sent, summed per target when due.
class NaiveNetwork {
 public:
  explicit NaiveNetwork(const NetworkSpec& spec) : spec_(spec) {
    for (const NeuronParams& p : spec.neurons) state_.push_back({kRestVoltage, p.b * kRestVoltage});
  }
  std::vector<std::uint32_t> step(const std::vector<float>& input) {
    const std::size_t n = state_.size();
    std::vector<std::uint32_t> fired;
    for (std::uint32_t i = 0; i < n; ++i)
      if (state_[i].v >= kPeakVoltage) fired.push_back(i);
    for (std::uint32_t j : fired)
      for (const Synapse& s : spec_.synapses)
        if (s.source == j) pending_.push_back({time_ + s.delay, s.target, s.weight});
    std::vector<float> pulses(n, 0.0f);
    std::vector<Pending> later;
    for (const Pending& p : pending_) {
      if (p.time == time_)
        pulses[p.target] += p.weight;
      else
        later.push_back(p);
    }
    pending_ = later;
    for (std::uint32_t i = 0; i < n; ++i)
      step_neuron(state_[i], spec_.neurons[i], spec_.bias[i] + input[i] + pulses[i], spec_.integration);
    ++time_;
    return fired;
  }
  const NeuronState& state(std::size_t i) const { return state_[i]; }

 private:
  struct Pending {
    std::uint64_t time;
    std::uint32_t target;
    float weight;
  };
  NetworkSpec spec_;
  std::vector<NeuronState> state_;
  std::vector<Pending> pending_;
  std::uint64_t time_ = 0;
};

TEST(SpikingNetworkTest, BitIdenticalToANaivePerNeuronLoop) {
  // 203 neurons: not a multiple of the vector width, so the scalar tail runs too.
  for (Integration scheme : {Integration::kPublished, Integration::kEuler}) {
    SCOPED_TRACE(to_string(scheme));
    const NetworkSpec spec = random_spec(7, 203, 10, scheme);
    auto net = SpikingNetwork::create(spec);
    ASSERT_TRUE(net.ok()) << net.error();
    SpikingNetwork& fast = net.value();
    NaiveNetwork naive(spec);
    kernel::RandomStream r(99);
    std::size_t spikes = 0;
    for (int t = 0; t < 1500; ++t) {
      std::vector<float> input(spec.neurons.size());
      for (float& x : input) x = static_cast<float>(r.normal(0, 3));
      for (std::size_t i = 0; i < input.size(); ++i) fast.input()[i] += input[i];
      const auto got = fast.step();
      const auto want = naive.step(input);
      ASSERT_EQ(std::vector<std::uint32_t>(got.begin(), got.end()), want) << "step " << t;
      spikes += want.size();
      for (std::size_t i = 0; i < spec.neurons.size(); ++i) {
        ASSERT_EQ(fast.v()[i], naive.state(i).v) << "step " << t << " neuron " << i;
        ASSERT_EQ(fast.u()[i], naive.state(i).u) << "step " << t << " neuron " << i;
      }
    }
    EXPECT_EQ(fast.time_ms(), 1500u);
    // A test of something: the network was busy (several Hz per neuron), not silent or saturated.
    EXPECT_GT(spikes, 203u * 3);
    EXPECT_LT(spikes, 203u * 1500 / 4);
  }
}

TEST(SpikingNetworkTest, StepClearsTheInputAndReturnsFiredAscending) {
  auto net = SpikingNetwork::create(random_spec(3, 64, 5, Integration::kPublished));
  ASSERT_TRUE(net.ok());
  SpikingNetwork& n = net.value();
  for (float& x : n.input()) x = 200.0f;  // every neuron crosses the peak in step 0
  EXPECT_TRUE(n.step().empty());
  for (float x : n.input()) EXPECT_EQ(x, 0.0f);
  const auto fired = n.step();
  ASSERT_EQ(fired.size(), 64u);
  for (std::uint32_t i = 0; i < 64; ++i) EXPECT_EQ(fired[i], i);
}

TEST(SpikingNetworkTest, PulsesArriveExactlyAfterTheirDelay) {
  // Neuron 0 fires once; it projects onto 1, 2, 3 with delays 0, 1 and 63 ms; neuron 4 is their
  // unconnected twin. A target's v leaves its twin's in the step its pulse is integrated.
  const std::uint32_t delays[] = {0, 1, kMaxDelay};
  NetworkSpec spec;
  spec.neurons.assign(5, params_of(NeuronClass::kRS));
  for (std::uint32_t k = 0; k < 3; ++k) spec.synapses.push_back({0, k + 1, 3.0f, delays[k]});
  auto net = SpikingNetwork::create(spec);
  ASSERT_TRUE(net.ok()) << net.error();
  SpikingNetwork& n = net.value();
  n.input()[0] = 500.0f;
  long fire_step = -1;
  long first_difference[3] = {-1, -1, -1};
  for (long t = 0; t < 100; ++t) {
    for (std::uint32_t j : n.step()) {
      ASSERT_EQ(j, 0u) << "only neuron 0 fires";
      if (fire_step < 0) fire_step = t;
    }
    for (int k = 0; k < 3; ++k)
      if (first_difference[k] < 0 && n.v()[k + 1] != n.v()[4]) first_difference[k] = t;
  }
  ASSERT_EQ(fire_step, 1);  // crossed during step 0, fires at the start of step 1
  for (int k = 0; k < 3; ++k) EXPECT_EQ(first_difference[k], fire_step + static_cast<long>(delays[k])) << delays[k];
}

TEST(SpikingNetworkTest, SpecRoundTripAndRowsKeepSpecOrder) {
  const NetworkSpec spec = random_spec(11, 50, 8, Integration::kEuler);
  auto net = SpikingNetwork::create(spec);
  ASSERT_TRUE(net.ok());
  EXPECT_EQ(net->size(), 50u);
  EXPECT_EQ(net->synapse_count(), spec.synapses.size());
  EXPECT_EQ(net->integration(), Integration::kEuler);
  for (std::uint32_t j = 0; j < 50; ++j) {
    std::vector<Synapse> row;
    for (const Synapse& s : spec.synapses)
      if (s.source == j) row.push_back(s);
    EXPECT_EQ(net->synapses_of(j), row) << j;
    EXPECT_EQ(net->params(j), spec.neurons[j]);
  }
  EXPECT_TRUE(net->synapses_of(50).empty());
  const NetworkSpec back = net->spec();
  EXPECT_EQ(back.neurons, spec.neurons);
  EXPECT_EQ(back.bias, spec.bias);
  EXPECT_EQ(back.synapses.size(), spec.synapses.size());
  auto again = SpikingNetwork::create(back);
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again->spec().synapses, back.synapses);
  for (std::uint32_t j = 0; j < 50; ++j) EXPECT_EQ(again->synapses_of(j), net->synapses_of(j));

  NetworkSpec no_bias = spec;
  no_bias.bias.clear();
  auto zero = SpikingNetwork::create(no_bias);
  ASSERT_TRUE(zero.ok());
  EXPECT_EQ(std::vector<float>(zero->bias().begin(), zero->bias().end()), std::vector<float>(50, 0.0f));
}

TEST(SpikingNetworkTest, ResetReplaysTheSameRaster) {
  auto net = SpikingNetwork::create(random_spec(5, 100, 10, Integration::kPublished));
  ASSERT_TRUE(net.ok());
  SpikingNetwork& n = net.value();
  auto run = [&n] {
    std::vector<std::uint32_t> raster;
    for (int t = 0; t < 300; ++t) {
      n.input()[static_cast<std::size_t>(t) % n.size()] += 20.0f;
      for (std::uint32_t j : n.step()) raster.push_back(static_cast<std::uint32_t>(t) * 1000 + j);
    }
    return raster;
  };
  const auto first = run();
  n.input()[3] = 7.0f;  // left over: reset clears it
  n.reset();
  EXPECT_EQ(n.time_ms(), 0u);
  for (std::size_t i = 0; i < n.size(); ++i) {
    EXPECT_EQ(n.v()[i], kRestVoltage);
    EXPECT_EQ(n.u()[i], n.params(static_cast<std::uint32_t>(i)).b * kRestVoltage);
  }
  EXPECT_FALSE(first.empty());
  EXPECT_EQ(run(), first);
}

std::string create_error(const NetworkSpec& spec) {
  auto net = SpikingNetwork::create(spec);
  return net.ok() ? std::string("(accepted)") : net.error();
}

TEST(SpikingNetworkTest, CreateRejectsBadSpecsNamingTheItem) {
  NetworkSpec good;
  good.neurons.assign(800, params_of(NeuronClass::kRS));
  for (std::uint32_t k = 0; k < 20; ++k) good.synapses.push_back({k, k + 1, 1.0f, k});
  ASSERT_TRUE(SpikingNetwork::create(good).ok());

  NetworkSpec s = good;
  s.synapses[12].target = 900;
  EXPECT_EQ(create_error(s), "synapse 12: target 900 out of range (network has 800 neurons)");
  s = good;
  s.synapses[3].source = 800;
  EXPECT_EQ(create_error(s), "synapse 3: source 800 out of range (network has 800 neurons)");
  s = good;
  s.synapses[5].delay = 64;
  EXPECT_EQ(create_error(s), "synapse 5: delay 64 ms out of range (0..63)");
  s = good;
  s.synapses[7].weight = std::numeric_limits<float>::quiet_NaN();
  EXPECT_NE(create_error(s).find("synapse 7: weight nan"), std::string::npos) << create_error(s);
  s = good;
  s.synapses[8].weight = -1001.0f;
  EXPECT_NE(create_error(s).find("synapse 8: weight"), std::string::npos) << create_error(s);
  s = good;
  s.bias.assign(799, 0.0f);
  EXPECT_EQ(create_error(s), "bias has 799 values, expected 0 or 800 (network has 800 neurons)");
  s = good;
  s.bias.assign(800, 0.0f);
  s.bias[17] = std::numeric_limits<float>::infinity();
  EXPECT_NE(create_error(s).find("bias 17:"), std::string::npos) << create_error(s);
  s = good;
  s.neurons[40].c = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(create_error(s), "neuron 40: parameter c is not finite");
  s = good;
  s.neurons.clear();
  s.synapses.clear();
  EXPECT_EQ(create_error(s), "network has no neurons");
}

}  // namespace
