// Scenario sessions on the lockstep executor (kernel/lockstep_executor.hpp): each robot's node on
// a lane of its own, the world runner, the radio and the events on the main lane. The shipped
// swarms (scenarios/swarm.yaml; scenarios/medea_swarm.yaml, whose robots meet over the radio too)
// give the same trajectories, bit for bit, with 1, 2 and 4 worker threads, and the same as on the
// single virtual-time executor; so does a swarm whose scenario events act between world steps.
#include <chrono>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "symb/kernel/lockstep_executor.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/sim/scenario_session.hpp"

#include "support/shipped_scenario.hpp"

namespace symb::sim {
namespace {

using namespace std::chrono_literals;

const std::string kScenarioDir = SYMB_SCENARIO_DIR;

struct LockstepOutcome {
  std::uint64_t hash = 1469598103934665603ull;  // FNV-1a over every pose and wheel speed per step
  std::uint64_t steps = 0;
  double distance = 0;  // cm, all robots
  RadioCounts radio;
  std::size_t events_done = 0;
};

void mix_bits(std::uint64_t& h, double v) {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &v, sizeof v);
  h = (h ^ bits) * 1099511628211ull;
}

// threads 0: the single VirtualTimeExecutor. `prefetch`: LockstepExecutor::Options::prefetch, a
// hint that must not change the run.
LockstepOutcome run_session(const Scenario& scenario, unsigned threads, kernel::Duration duration,
                            bool prefetch = false) {
  LockstepOutcome out;
  std::unique_ptr<kernel::Executor> executor;
  if (threads == 0)
    executor = std::make_unique<kernel::VirtualTimeExecutor>();
  else
    executor = std::make_unique<kernel::LockstepExecutor>(kernel::LockstepExecutor::Options{
        .threads = threads, .quantum = scenario.control_period, .prefetch = prefetch});
  auto created = ScenarioSession::create(scenario, *executor);
  EXPECT_TRUE(created.ok()) << (created.ok() ? "" : created.error());
  if (!created.ok()) return out;
  ScenarioSession& session = **created;
  session.runner().add_observer([&out](const StepRecord& r) {
    ++out.steps;
    for (const RobotStep& s : r.robots) {
      mix_bits(out.hash, s.state.pose.x);
      mix_bits(out.hash, s.state.pose.y);
      mix_bits(out.hash, s.state.pose.theta);
      mix_bits(out.hash, s.state.left_speed);
      mix_bits(out.hash, s.state.right_speed);
    }
  });
  session.start();
  // In slices ending off and on world steps, as `symb run` does.
  const kernel::Time end = kernel::Time{duration};
  for (kernel::Time t{0}; t < end;) {
    t = std::min(end, t + 1010ms);
    if (threads == 0)
      static_cast<kernel::VirtualTimeExecutor&>(*executor).run_until(t);
    else
      static_cast<kernel::LockstepExecutor&>(*executor).run_until(t);
  }
  session.stop();
  for (std::size_t i = 0; i < session.robot_count(); ++i) out.distance += session.world().state(i).distance;
  if (session.radio()) out.radio = session.radio()->counts();
  if (session.events()) out.events_done = session.events()->done();
  return out;
}

TEST(LockstepSession, SwarmIsTheSameWithOneTwoAndFourThreads) {
  const Scenario swarm = test::load_shipped("swarm.yaml");
  const LockstepOutcome one = run_session(swarm, 1, 10s);
  EXPECT_EQ(one.steps, 333u);
  EXPECT_GT(one.distance, 12 * 50.0);  // the robots really drive: 50 cm each on average at least
  for (unsigned threads : {2u, 4u}) {
    const LockstepOutcome n = run_session(swarm, threads, 10s);
    EXPECT_EQ(n.hash, one.hash) << threads << " threads";
    EXPECT_EQ(n.steps, one.steps);
  }
  EXPECT_EQ(run_session(swarm, 2, 10s, true).hash, one.hash) << "2 threads, the lanes prefetched";
  EXPECT_EQ(run_session(swarm, 0, 10s).hash, one.hash) << "the single virtual-time executor";
}

TEST(LockstepSession, RadioSwarmIsTheSameWithOneTwoAndFourThreads) {
  const Scenario medea = test::load_shipped("medea_swarm.yaml");
  const LockstepOutcome one = run_session(medea, 1, 20s);
  EXPECT_GT(one.radio.delivered, 100u);  // the robots do meet over the radio
  for (unsigned threads : {2u, 4u}) {
    // With 4 threads the lanes' state is prefetched too (a hint: the same run).
    const LockstepOutcome n = run_session(medea, threads, 20s, threads == 4);
    EXPECT_EQ(n.hash, one.hash) << threads << " threads";
    EXPECT_EQ(n.radio.transmitted, one.radio.transmitted);
    EXPECT_EQ(n.radio.delivered, one.radio.delivered);
    EXPECT_EQ(n.radio.dropped, one.radio.dropped);
  }
  const LockstepOutcome single = run_session(medea, 0, 20s);
  EXPECT_EQ(single.hash, one.hash) << "the single virtual-time executor";
  EXPECT_EQ(single.radio.delivered, one.radio.delivered);
}

// Scenario events run on the main lane, at their own instants, between world steps too: a shell
// line on a robot's node while its lane is idle. Same run for every number of threads, and the
// same as on the single executor, where the event interleaves with the robots' own events.
TEST(LockstepSession, EventsBetweenWorldStepsAreTheSameWithAnyNumberOfThreads) {
  std::ifstream in(kScenarioDir + "/swarm.yaml");
  std::stringstream text;
  text << in.rdbuf();
  const std::string yaml = text.str() +
                           "events:\n"
                           "  - {at: 1015ms, robot: thymio3, shell: suspend controller}\n"
                           "  - {at: 1s, robot: thymio5, shell: \"ioctl wheels close\"}\n"
                           "  - {at: 2507ms, robot: thymio3, shell: resume controller}\n";
  auto parsed = parse_scenario(yaml, kScenarioDir + "/swarm.yaml");
  ASSERT_TRUE(parsed.ok()) << parsed.error();
  const LockstepOutcome one = run_session(*parsed, 1, 4s);
  EXPECT_EQ(one.events_done, 3u);
  EXPECT_NE(one.hash, run_session(test::load_shipped("swarm.yaml"), 1, 4s).hash);  // the events change the run
  EXPECT_EQ(run_session(*parsed, 2, 4s).hash, one.hash);
  EXPECT_EQ(run_session(*parsed, 4, 4s).hash, one.hash);
  EXPECT_EQ(run_session(*parsed, 0, 4s).hash, one.hash) << "the single virtual-time executor";
}

}  // namespace
}  // namespace symb::sim
