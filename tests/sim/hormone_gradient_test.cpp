// Hormones across robots (scenarios/hormone_gradient.yaml): five docked modules each step one
// compartment of an AHHS network and exchange levels with their neighbours over the organism bus.
// The morphogen made at the head must settle into the steady state of the network's own equations,
// solved here as a linear system, and the exchange must cross the bus as frames.
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/sim/mujoco/organism_session.hpp"
#include "symb/sim/scenario.hpp"

namespace symb::sim::mujoco {
namespace {

using namespace std::chrono_literals;
constexpr std::size_t kChain = 5;

// The fixed point of one AHHS step of scenarios/ahhs/chain_gradient.ahhs (docs/ahhs.md, "The
// model"): local update L = A H + b (decay 0.1 everywhere; at the head the rule adds 0.05 (1 - H)),
// then diffusion H' = M L with M = I - D * Laplacian(chain), D = 0.2. So H = M (A H + b), i.e.
// (I - M A) H = M b, solved by Gaussian elimination.
std::array<double, kChain> steady_state() {
  constexpr double kDecay = 0.1, kMake = 0.05, kDiffusion = 0.2;
  double m[kChain][kChain] = {};
  for (std::size_t i = 0; i < kChain; ++i) {
    m[i][i] = 1;
    for (std::size_t j : {i - 1, i + 1}) {
      if (j >= kChain) continue;  // i - 1 wraps for i = 0
      m[i][i] -= kDiffusion;
      m[i][j] += kDiffusion;
    }
  }
  std::array<double, kChain> a{}, b{};
  for (std::size_t i = 0; i < kChain; ++i) a[i] = 1 - kDecay;
  a[0] -= kMake;
  b[0] = kMake;
  double sys[kChain][kChain + 1] = {};
  for (std::size_t i = 0; i < kChain; ++i) {
    for (std::size_t j = 0; j < kChain; ++j) sys[i][j] = (i == j ? 1.0 : 0.0) - m[i][j] * a[j];
    for (std::size_t j = 0; j < kChain; ++j) sys[i][kChain] += m[i][j] * b[j];
  }
  for (std::size_t c = 0; c < kChain; ++c) {  // the matrix is diagonally dominant: no pivoting
    for (std::size_t r = c + 1; r < kChain; ++r) {
      const double f = sys[r][c] / sys[c][c];
      for (std::size_t k = c; k <= kChain; ++k) sys[r][k] -= f * sys[c][k];
    }
  }
  std::array<double, kChain> h{};
  for (std::size_t r = kChain; r-- > 0;) {
    double v = sys[r][kChain];
    for (std::size_t k = r + 1; k < kChain; ++k) v -= sys[r][k] * h[k];
    h[r] = v / sys[r][r];
  }
  return h;
}

TEST(HormoneGradient, AMorphogenMadeAtTheHeadSettlesIntoTheSteadyStateAlongFiveModules) {
  auto sc = load_scenario(std::string(SYMB_SCENARIO_DIR) + "/hormone_gradient.yaml");
  ASSERT_TRUE(sc.ok()) << sc.error();
  kernel::VirtualTimeExecutor ex;
  auto made = OrganismSession::create(*sc, ex);
  ASSERT_TRUE(made.ok()) << made.error();
  OrganismSession& s = **made;
  std::array<double, kChain> level{};
  std::array<std::uint64_t, kChain> steps{};
  for (std::size_t m = 0; m < kChain; ++m)
    s.robot(m).node().set_probe_sink([&level, &steps, m](const os::ProbeSample& p) {
      if (p.channel.starts_with("hormones/") && p.values.size() == 1) {
        level[m] = p.values[0];
        ++steps[m];
      }
    });
  s.start();
  ex.run_for(20s);
  const auto expected = steady_state();
  for (std::size_t m = 0; m < kChain; ++m) {
    std::printf("module %zu: %.6f (steady state %.6f), %llu steps\n", m, level[m], expected[m],
                static_cast<unsigned long long>(steps[m]));
    // Float levels against double arithmetic; the approach to the fixed point is 0.9^n.
    EXPECT_NEAR(level[m], expected[m], 1e-5) << "module " << m;
    EXPECT_GE(steps[m], 660u);  // one per control period of 30 ms
    if (m > 0) {
      EXPECT_LT(level[m], level[m - 1]);
    }
  }
  // Every step each compartment sends its levels to each neighbour: 8 remote hooks.
  const auto hooks = s.bus()->hooks();
  ASSERT_EQ(hooks.size(), 8u);
  for (const auto& h : hooks) {
    EXPECT_TRUE(h.books.closes());
    EXPECT_GE(h.books.delivered, 660u) << h.sender << " -> " << h.receiver;
    EXPECT_EQ(h.books.dropped(), 0u) << h.sender << " -> " << h.receiver;
  }
}

}  // namespace
}  // namespace symb::sim::mujoco
