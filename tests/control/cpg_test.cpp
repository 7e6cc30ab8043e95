// Central pattern generators: the phase oscillator model against its closed-form behaviour (free
// running, the fixed point of a coupled chain, latency carried forward, neighbours timing out),
// and the `oscillator` task type in a node under virtual time: five tasks hooked into a chain lock
// into a travelling wave, drive their joint targets from their phases, count what they ignore.
#include <cmath>
#include <memory>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "symb/control/control_task_types.hpp"
#include "symb/control/cpg/oscillator_task.hpp"
#include "symb/control/cpg/phase_oscillator.hpp"
#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/os/param.hpp"

namespace symb::control::cpg {
namespace {

using namespace std::chrono_literals;
constexpr double kPi = std::numbers::pi;

// theta_a - theta_b folded into (-pi, pi].
double phase_difference(double a, double b) {
  double d = std::fmod(a - b, 2 * kPi);
  if (d > kPi) d -= 2 * kPi;
  if (d <= -kPi) d += 2 * kPi;
  return d;
}

TEST(PhaseOscillator, RunsFreeAtItsFrequency) {
  PhaseOscillator o({.frequency = 0.7, .initial_phase = 1.0});
  o.step(0.0);
  o.step(3.3);
  EXPECT_NEAR(phase_difference(o.phase(), 1.0 + 2 * kPi * 0.7 * 3.3), 0.0, 1e-9);
  EXPECT_NEAR(o.output(), 0.5 * std::sin(o.phase()), 1e-12);
  EXPECT_EQ(o.coupled(), 0);
}

TEST(PhaseOscillator, HearsOnlyItsChainNeighbours) {
  PhaseOscillator o({.id = 3});
  EXPECT_TRUE(o.hear(2, 0.1, 0));
  EXPECT_TRUE(o.hear(4, 0.1, 0));
  EXPECT_FALSE(o.hear(3, 0.1, 0));
  EXPECT_FALSE(o.hear(5, 0.1, 0));
  EXPECT_FALSE(o.hear(1, 0.1, 0));
  EXPECT_FALSE(o.hear(2, std::nan(""), 0));
  EXPECT_FALSE(o.hear(2, 0.1, INFINITY));
}

// Steps a chain of n oscillators together, each hearing its neighbours' phases as they were
// `delay` seconds ago (a link's latency), and returns the phases after `duration`.
std::vector<double> run_chain(int n, double lag, double delay, double duration, std::uint64_t seed) {
  kernel::RandomStream random(seed);
  std::vector<PhaseOscillator> chain;
  for (int i = 0; i < n; ++i)
    chain.emplace_back(OscillatorParams{
        .id = i, .frequency = 0.5, .coupling = 4.0, .lag = lag, .initial_phase = random.uniform(0.0, 2 * kPi)});
  constexpr double kDt = 0.02;
  const auto steps = static_cast<int>(duration / kDt);
  const int delay_steps = static_cast<int>(std::lround(delay / kDt));
  std::vector<std::vector<double>> history;  // phases at each step, for the delayed messages
  for (int k = 0; k <= steps; ++k) {
    const double t = k * kDt;
    std::vector<double> phases;
    for (auto& o : chain) {
      o.step(t);
      phases.push_back(o.phase());
    }
    history.push_back(phases);
    const int sent = k - delay_steps;
    if (sent < 0) continue;
    for (int i = 0; i < n; ++i) {
      if (i > 0) chain[i].hear(i - 1, history[sent][i - 1], sent * kDt);
      if (i + 1 < n) chain[i].hear(i + 1, history[sent][i + 1], sent * kDt);
    }
  }
  return history.back();
}

TEST(PhaseOscillator, AChainLocksEachOneLagBehindTheOneBefore) {
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const auto phases = run_chain(5, kPi / 2, 0.0, 20.0, seed);
    for (std::size_t i = 1; i < phases.size(); ++i)
      EXPECT_NEAR(phase_difference(phases[i - 1], phases[i]), kPi / 2, 0.01) << "seed " << seed << " pair " << i;
  }
}

TEST(PhaseOscillator, ALinksLatencyIsCarriedForward) {
  // 100 ms is a fifth of a radian at 0.5 Hz: without carrying the heard phase forward the chain
  // would settle that far from the lag.
  const auto phases = run_chain(5, kPi / 3, 0.1, 30.0, 9);
  for (std::size_t i = 1; i < phases.size(); ++i)
    EXPECT_NEAR(phase_difference(phases[i - 1], phases[i]), kPi / 3, 0.01) << "pair " << i;
}

TEST(PhaseOscillator, ASilentNeighbourStopsPullingAfterTheTimeout) {
  PhaseOscillator o({.id = 1, .frequency = 1.0, .coupling = 4.0, .neighbour_timeout = 0.5});
  o.step(0.0);
  o.hear(0, 2.0, 0.0);
  o.step(0.4);
  EXPECT_EQ(o.coupled(), 1);
  o.step(0.6);
  EXPECT_EQ(o.coupled(), 0);
  const double before = o.phase();
  o.step(1.6);  // free running now: exactly one turn
  EXPECT_NEAR(phase_difference(o.phase(), before), 0.0, 1e-9);
}

// --- the task ---------------------------------------------------------------------------------------

struct CpgRig {
  kernel::VirtualTimeExecutor ex;
  os::TaskTypeRegistry types;
  os::Node node;
  std::vector<os::TaskId> ids;
  std::vector<OscillatorTask*> tasks;

  CpgRig() : node(ex, {.name = "chain", .seed = 3, .types = &types}) {
    EXPECT_TRUE(register_control_task_types(types, {}).ok());
  }
  // An oscillator made in code, ticking at 20 ms like the type's default.
  os::TaskId add(const std::string& name, OscillatorOptions o) {
    auto task = std::make_unique<OscillatorTask>(o);
    tasks.push_back(task.get());
    auto id = node.create(name, std::move(task), {.period = 20ms, .queue_capacity = 8});
    EXPECT_TRUE(id.ok());
    ids.push_back(*id);
    return *id;
  }
  OscillatorTask& task(std::size_t i) { return *tasks.at(i); }
  kernel::Status post(os::TaskId to, os::Port port, std::vector<float> v) {
    os::Message m;
    m.port = port;
    m.payload.assign(v);
    return node.post(to, m);
  }
};

TEST(OscillatorTask, FiveTasksHookedIntoAChainMakeATravellingWave) {
  CpgRig rig;
  for (int i = 0; i < 5; ++i)
    rig.add("osc" + std::to_string(i), {.id = i, .frequency = 0.5, .lag = 0.7, .initial_phase = 1.3 * i});
  for (int i = 0; i + 1 < 5; ++i) {
    ASSERT_TRUE(rig.node.hook(rig.ids[i], rig.ids[i + 1], {.port = kPhasePort}).ok());
    ASSERT_TRUE(rig.node.hook(rig.ids[i + 1], rig.ids[i], {.port = kPhasePort}).ok());
  }
  rig.ex.run_for(20s);
  for (int i = 1; i < 5; ++i)
    EXPECT_NEAR(phase_difference(rig.task(i - 1).phase(), rig.task(i).phase()), 0.7, 0.02) << i;
  const auto s = rig.task(2).stats();
  EXPECT_EQ(s.steps, 1000u);  // 20 s at the default 20 ms
  EXPECT_GE(s.heard, 2 * 1000u - 2);
  EXPECT_EQ(s.foreign, 0u);
  EXPECT_EQ(s.ignored, 0u);
}

// Keeps the last joint target it was sent.
class CpgJoint : public os::Task {
 public:
  float target = NAN;
  int messages = 0;

 protected:
  void on_message(const os::Message& m) override {
    ASSERT_EQ(m.numbers().size(), 1u);
    target = m.numbers()[0];
    ++messages;
  }
};

TEST(OscillatorTask, DrivesItsJointFromItsPhaseAndCountsWhatItIgnores) {
  CpgRig rig;
  const os::TaskId osc = rig.add("osc", {.id = 1, .frequency = 1, .amplitude = 0.4, .offset = 0.1});
  auto joint_task = std::make_unique<CpgJoint>();
  CpgJoint* joint = joint_task.get();
  auto jid = rig.node.create("joint", std::move(joint_task));
  ASSERT_TRUE(jid.ok());
  ASSERT_TRUE(rig.node.hook(osc, *jid, {.port = kJointTargetPort}).ok());
  rig.ex.run_for(1010ms);
  EXPECT_EQ(joint->messages, 50);  // ticks at 20, 40, ..., 1000 ms: the first one period after the start
  EXPECT_NEAR(joint->target, 0.1 + 0.4 * std::sin(rig.task(0).phase()), 1e-6);
  ASSERT_TRUE(rig.post(osc, kPhasePort, {0.5f}).ok());
  ASSERT_TRUE(rig.post(osc, kPhasePort, {1.5f, 0.1f}).ok());
  ASSERT_TRUE(rig.post(osc, kPhasePort, {7.0f, 0.1f}).ok());
  ASSERT_TRUE(rig.post(osc, 0, {0.0f, 0.1f}).ok());
  ASSERT_TRUE(rig.post(osc, kPhasePort, {2.0f, 0.1f}).ok());
  rig.ex.run_for(10ms);
  const auto s = rig.task(0).stats();
  EXPECT_EQ(s.ignored, 3u);
  EXPECT_EQ(s.foreign, 1u);
  EXPECT_EQ(s.heard, 1u);
}

TEST(OscillatorTask, ARandomPhaseComesFromTheSeedAndTheName) {
  auto phase_after_start = [](std::uint64_t seed, const char* name) {
    kernel::VirtualTimeExecutor ex;
    os::Node node(ex, {.name = "m", .seed = seed});
    auto task = std::make_unique<OscillatorTask>(OscillatorOptions{.random_phase = true});
    OscillatorTask* t = task.get();
    EXPECT_TRUE(node.create(name, std::move(task), {.period = 20ms}).ok());
    ex.run_for(1ms);  // started, not yet ticked
    return t->phase();
  };
  EXPECT_EQ(phase_after_start(1, "osc"), phase_after_start(1, "osc"));
  EXPECT_NE(phase_after_start(1, "osc"), phase_after_start(2, "osc"));
  EXPECT_NE(phase_after_start(1, "osc"), phase_after_start(1, "osc2"));
  EXPECT_NE(phase_after_start(1, "osc"), 0.0);
}

TEST(OscillatorTask, TheTypeChecksItsParameters) {
  CpgRig rig;
  auto create = [&](std::string_view text) {
    auto params = os::parse_param_assignments(text);
    EXPECT_TRUE(params.ok());
    return rig.node.create("oscillator", "osc", *params);
  };
  auto bad = create("lag=7");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().find("lag"), std::string::npos) << bad.error();
  auto good = create("frequency=2 id=4");
  ASSERT_TRUE(good.ok()) << good.error();
  EXPECT_TRUE(rig.node.set_parameter(*good, "frequency", "1.5").ok());
  EXPECT_FALSE(rig.node.set_parameter(*good, "amplitude", "4").ok());
  rig.ex.run_for(100ms);
  auto values = rig.node.parameters(*good);
  ASSERT_TRUE(values.ok());
  EXPECT_DOUBLE_EQ(values->real("frequency"), 1.5);
  EXPECT_EQ(values->integer("id"), 4);
}

}  // namespace
}  // namespace symb::control::cpg
