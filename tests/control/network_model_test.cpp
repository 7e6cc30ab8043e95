// The network models against values worked out by hand: a 2-2-1 tanh MLP, an Elman network's
// context over two steps, a CTRNN neuron's Euler steps and its steady state; genome sizes and
// order, and bad genomes and topologies refused.
#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "symb/control/network/network.hpp"

namespace symb::control::network {
namespace {

Network make(Kind kind, std::size_t inputs, std::vector<std::size_t> layers, Activation a = Activation::kTanh) {
  auto n = Network::create({kind, inputs, std::move(layers), a});
  EXPECT_TRUE(n.ok()) << (n ? "" : n.error());
  return std::move(n).value();
}

double sigma(double x) { return 1 / (1 + std::exp(-x)); }

TEST(NetworkModel, MlpTwoTwoOneByHand) {
  Network n = make(Kind::kMlp, 2, {2, 1});
  ASSERT_EQ(n.genome_size(), 9u);  // (2 + 1) * 2 + (2 + 1) * 1
  // Per neuron: weights from below, then bias.
  const std::vector<float> g{0.5f, -1.0f, 0.1f, 1.0f, 1.0f, -0.5f, 1.0f, -1.0f, 0.2f};
  ASSERT_TRUE(n.set_genome(g).ok());
  const std::vector<float> x{1.0f, 0.5f};
  const auto out = n.step(x);
  ASSERT_EQ(out.size(), 1u);
  // h0 = tanh(0.5 - 0.5 + 0.1), h1 = tanh(1 + 0.5 - 0.5), o = tanh(h0 - h1 + 0.2)
  const double h0 = std::tanh(0.1), h1 = std::tanh(1.0), o = std::tanh(h0 - h1 + 0.2);
  EXPECT_NEAR(out[0], o, 1e-6);
  EXPECT_NEAR(out[0], -0.4316528, 1e-6);
  ASSERT_EQ(n.layer_count(), 3u);
  EXPECT_EQ(n.layer_name(0), "input");
  EXPECT_EQ(n.layer_name(1), "hidden1");
  EXPECT_EQ(n.layer_name(2), "output");
  EXPECT_NEAR(n.layer(1)[0], h0, 1e-6);
  EXPECT_NEAR(n.layer(1)[1], h1, 1e-6);
  // Feed-forward: no memory, the same input gives the same output.
  EXPECT_NEAR(n.step(x)[0], o, 1e-6);
}

TEST(NetworkModel, PerceptronSigmoidAndLinear) {
  Network s = make(Kind::kMlp, 2, {1}, Activation::kSigmoid);
  ASSERT_TRUE(s.set_genome(std::vector<float>{2.0f, -1.0f, 0.5f}).ok());
  EXPECT_NEAR(s.step(std::vector<float>{1.0f, 1.0f})[0], sigma(1.5), 1e-6);
  Network l = make(Kind::kMlp, 2, {1}, Activation::kLinear);
  ASSERT_TRUE(l.set_genome(std::vector<float>{2.0f, -1.0f, 0.5f}).ok());
  EXPECT_NEAR(l.step(std::vector<float>{3.0f, 1.0f})[0], 5.5, 1e-6);
}

TEST(NetworkModel, ElmanStepUsesItsContext) {
  Network n = make(Kind::kElman, 1, {1, 1});
  ASSERT_EQ(n.genome_size(), 5u);  // hidden: w_in, w_context, bias; output: w, bias
  ASSERT_TRUE(n.set_genome(std::vector<float>{1.0f, 0.5f, 0.0f, 2.0f, 0.0f}).ok());
  // Step 1, context 0: h = tanh(1), o = tanh(2 h).
  const double h1 = std::tanh(1.0);
  EXPECT_NEAR(n.step(std::vector<float>{1.0f})[0], std::tanh(2 * h1), 1e-6);
  // Step 2, input 0: only the context drives: h = tanh(0.5 h1).
  const double h2 = std::tanh(0.5 * h1);
  EXPECT_NEAR(n.step(std::vector<float>{0.0f})[0], std::tanh(2 * h2), 1e-6);
  EXPECT_NEAR(n.step(std::vector<float>{0.0f})[0], std::tanh(2 * std::tanh(0.5 * h2)), 1e-6);
  // reset() forgets the context: input 0 gives tanh(0) = 0.
  n.reset();
  EXPECT_NEAR(n.step(std::vector<float>{0.0f})[0], 0.0, 1e-9);
}

TEST(NetworkModel, CtrnnEulerStepByHand) {
  Network n = make(Kind::kCtrnn, 1, {1, 1});
  ASSERT_EQ(n.genome_size(), 3u);  // v (input), w (self), theta
  ASSERT_TRUE(n.set_genome(std::vector<float>{1.0f, 1.0f, 0.0f}).ok());
  ASSERT_TRUE(n.set_time_constants(std::vector<float>{0.1f}).ok());
  ASSERT_TRUE(n.set_step(0.03).ok());
  EXPECT_NEAR(n.outputs()[0], 0.5, 1e-7);  // at rest: sigma(0 + theta)
  // y1 = 0 + dt/tau (-0 + w sigma(0) + v x) = 0.3 (0.5 + 0.5)
  const std::vector<float> x{0.5f};
  EXPECT_NEAR(n.step(x)[0], sigma(0.3), 1e-6);
  EXPECT_NEAR(n.layer(1)[0], 0.3, 1e-6);
  EXPECT_EQ(n.layer_name(1), "state");
  // y2 = y1 + 0.3 (-y1 + sigma(y1) + 0.5)
  const double y2 = 0.3 + 0.3 * (-0.3 + sigma(0.3) + 0.5);
  n.step(x);
  EXPECT_NEAR(n.layer(1)[0], y2, 1e-6);
  EXPECT_NEAR(n.layer(1)[0], 0.5323328, 1e-6);
}

TEST(NetworkModel, CtrnnSingleNeuronSteadyState) {
  // Without self-coupling, y settles at the input drive I = v x.
  Network free = make(Kind::kCtrnn, 1, {1, 1});
  ASSERT_TRUE(free.set_genome(std::vector<float>{2.0f, 0.0f, -1.0f}).ok());
  ASSERT_TRUE(free.set_time_constants(std::vector<float>{0.1f}).ok());
  for (int k = 0; k < 300; ++k) free.step(std::vector<float>{0.25f});
  EXPECT_NEAR(free.layer(1)[0], 0.5, 1e-5);
  EXPECT_NEAR(free.outputs()[0], sigma(0.5 - 1.0), 1e-5);
  // With a self-weight w, the fixed point solves y = w sigma(y + theta) + I (found by bisection).
  const double w = 1.5, theta = -0.5, input = 0.2;
  double lo = -10, hi = 10;
  for (int k = 0; k < 200; ++k) {
    const double mid = (lo + hi) / 2;
    ((-mid + w * sigma(mid + theta) + input) > 0 ? lo : hi) = mid;
  }
  Network self = make(Kind::kCtrnn, 1, {1, 1});
  ASSERT_TRUE(self.set_genome(std::vector<float>{1.0f, static_cast<float>(w), static_cast<float>(theta)}).ok());
  ASSERT_TRUE(self.set_time_constants(std::vector<float>{0.2f}).ok());
  for (int k = 0; k < 1000; ++k) self.step(std::vector<float>{static_cast<float>(input)});
  EXPECT_NEAR(self.layer(1)[0], lo, 1e-4);
}

TEST(NetworkModel, CtrnnGenomeOrderAcrossNeurons) {
  // Two neurons, one input, neuron 1 read out. Neuron 1 only listens to neuron 0 (w_01 = 4).
  Network n = make(Kind::kCtrnn, 1, {2, 1});
  ASSERT_EQ(n.genome_size(), 8u);  // 2 * (1 + 2 + 1)
  // neuron 0: v=1, w_00=0, w_10=0, theta=0; neuron 1: v=0, w_01=4, w_11=0, theta=-2
  ASSERT_TRUE(n.set_genome(std::vector<float>{1, 0, 0, 0, 0, 4, 0, -2}).ok());
  ASSERT_TRUE(n.set_time_constants(std::vector<float>{0.03f, 0.06f}).ok());
  n.step(std::vector<float>{1.0f});
  // dt/tau = 1 for neuron 0: y0 = 1; neuron 1 saw sigma(0 + 0) = 0.5 of the old state: y1 = 0.5 * 4 * 0.5
  EXPECT_NEAR(n.layer(1)[0], 1.0, 1e-6);
  EXPECT_NEAR(n.layer(1)[1], 1.0, 1e-6);
  EXPECT_NEAR(n.outputs()[0], sigma(1.0 - 2.0), 1e-6);
}

TEST(NetworkModel, GenomeSizesAndRoundTrip) {
  EXPECT_EQ(genome_size({Kind::kMlp, 7, {2}, Activation::kTanh}), 16u);  // the (1+1)-online perceptron
  EXPECT_EQ(genome_size({Kind::kMlp, 7, {4, 2}, Activation::kTanh}), 8u * 4 + 5 * 2);
  EXPECT_EQ(genome_size({Kind::kElman, 7, {4, 2}, Activation::kTanh}), (7u + 4 + 1) * 4 + 5 * 2);
  EXPECT_EQ(genome_size({Kind::kCtrnn, 7, {4, 2}, Activation::kTanh}), 4u * (7 + 4 + 1));
  Network n = make(Kind::kElman, 3, {2, 2});
  std::vector<float> g(n.genome_size());
  EXPECT_FALSE(Network::from_genome({Kind::kElman, 3, {2, 2}, Activation::kTanh}, std::vector<float>(3)).ok());
  for (std::size_t k = 0; k < g.size(); ++k) g[k] = 0.1f * static_cast<float>(k) - 1.0f;
  ASSERT_TRUE(n.set_genome(g).ok());
  EXPECT_EQ(std::vector<float>(n.genome().begin(), n.genome().end()), g);
  auto built = Network::from_genome({Kind::kElman, 3, {2, 2}, Activation::kTanh}, g);
  ASSERT_TRUE(built.ok()) << built.error();
  EXPECT_EQ(std::vector<float>(built->genome().begin(), built->genome().end()), g);
  const std::vector<float> x{0.3f, -0.7f, 1.0f};
  EXPECT_EQ(built.value().step(x)[1], n.step(x)[1]);
}

TEST(NetworkModel, BadGenomesAndTopologiesRefused) {
  Network n = make(Kind::kMlp, 2, {1});
  auto st = n.set_genome(std::vector<float>{1.0f, 2.0f});
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().find("has 3 values, got 2"), std::string::npos) << st.error();
  EXPECT_FALSE(n.set_genome(std::vector<float>{1.0f, std::numeric_limits<float>::quiet_NaN(), 0.0f}).ok());
  EXPECT_FALSE(n.set_genome(std::vector<float>{1.0f, std::numeric_limits<float>::infinity(), 0.0f}).ok());
  EXPECT_FALSE(Network::create({Kind::kMlp, 0, {1}, Activation::kTanh}).ok());
  EXPECT_FALSE(Network::create({Kind::kMlp, 2, {}, Activation::kTanh}).ok());
  EXPECT_FALSE(Network::create({Kind::kMlp, 2, {0}, Activation::kTanh}).ok());
  EXPECT_FALSE(Network::create({Kind::kMlp, 2, {65}, Activation::kTanh}).ok());
  EXPECT_FALSE(Network::create({Kind::kElman, 2, {2}, Activation::kTanh}).ok());
  EXPECT_FALSE(Network::create({Kind::kCtrnn, 2, {2}, Activation::kTanh}).ok());
  EXPECT_FALSE(Network::create({Kind::kCtrnn, 2, {2, 3}, Activation::kTanh}).ok());
  Network c = make(Kind::kCtrnn, 1, {2, 1});
  EXPECT_FALSE(c.set_time_constants(std::vector<float>{1, 2, 3}).ok());
  EXPECT_FALSE(c.set_time_constants(std::vector<float>{0.0f}).ok());
  EXPECT_FALSE(c.set_step(-0.01).ok());
}

TEST(NetworkModel, OutputsStayFiniteOnWildInputAndWeights) {
  Network lin = make(Kind::kMlp, 2, {3, 2}, Activation::kLinear);
  std::vector<float> g(lin.genome_size(), 3e38f);
  ASSERT_TRUE(lin.set_genome(g).ok());
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (float v : lin.step(std::vector<float>{3e38f, nan})) EXPECT_TRUE(std::isfinite(v));
  Network c = make(Kind::kCtrnn, 2, {3, 2});
  ASSERT_TRUE(c.set_genome(std::vector<float>(c.genome_size(), 3e38f)).ok());
  ASSERT_TRUE(c.set_step(10.0).ok());  // an Euler step far longer than tau
  for (int k = 0; k < 10; ++k)
    for (float v : c.step(std::vector<float>{1e30f, -1e30f})) EXPECT_TRUE(std::isfinite(v));
}

}  // namespace
}  // namespace symb::control::network
