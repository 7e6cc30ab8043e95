// MDL2e interpreter semantics, golden: nesting, timers against a fake clock, interrupt precedence
// (outer before inner), looping, plan end, task actions, bounded work per step.
#include <array>

#include <gtest/gtest.h>

#include "mdl2e_test_support.hpp"

namespace symb::control::mdl2e {
namespace {

using testing::atom;
using testing::events;
using testing::ms;
using testing::must_compile;

const InterruptInputs kNone{};
InterruptInputs bits(std::uint64_t b) { return InterruptInputs{{}, b}; }

TEST(Mdl2eInterpreter, NestingBehaviourInBehaviourInPlan) {
  const Program p = must_compile(R"(
plan p {
  atom forward(10) for 100ms
  behaviour outer {
    atom turn(5) for 50ms
    behaviour inner { atom wheels(1, 2) for 30ms  atom stop for 20ms }
  }
  atom backward(3) for 10ms
})");
  Interpreter in(p);
  auto o = in.step(ms(0), kNone);
  EXPECT_EQ(atom(o), "forward(10)");
  EXPECT_EQ(events(o), "started:p started:forward");
  EXPECT_DOUBLE_EQ(o.left, 10);
  EXPECT_DOUBLE_EQ(o.right, 10);
  o = in.step(ms(99), kNone);
  EXPECT_EQ(atom(o), "forward(10)");
  EXPECT_EQ(events(o), "");
  o = in.step(ms(100), kNone);
  EXPECT_EQ(atom(o), "turn(5)");
  EXPECT_EQ(events(o), "timed_out:forward started:outer started:turn");
  EXPECT_DOUBLE_EQ(o.left, -5);
  EXPECT_DOUBLE_EQ(o.right, 5);
  o = in.step(ms(150), kNone);
  EXPECT_EQ(atom(o), "wheels(1,2)");
  EXPECT_EQ(events(o), "timed_out:turn started:inner started:wheels");
  EXPECT_EQ(in.active_path().size(), 4u);  // plan, outer, inner, atom
  o = in.step(ms(180), kNone);
  EXPECT_EQ(atom(o), "stop");
  o = in.step(ms(200), kNone);
  EXPECT_EQ(atom(o), "backward(3)");
  EXPECT_EQ(events(o), "timed_out:stop completed:inner completed:outer started:backward");
  EXPECT_DOUBLE_EQ(o.left, -3);
  o = in.step(ms(210), kNone);
  EXPECT_EQ(atom(o), "ended");
  EXPECT_EQ(events(o), "timed_out:backward completed:p plan_ended:p");
}

TEST(Mdl2eInterpreter, TimersAreExactAndDoNotDrift) {
  const Program p = must_compile("plan p { atom forward(1) for 100ms atom turn(1) for 100ms atom stop for 100ms }");
  Interpreter in(p);
  EXPECT_EQ(atom(in.step(ms(0), kNone)), "forward(1)");
  // Seen late (150 ms), but turn started at forward's deadline, 100 ms: it ends at 200 ms.
  EXPECT_EQ(atom(in.step(ms(150), kNone)), "turn(1)");
  EXPECT_EQ(atom(in.step(ms(199), kNone)), "turn(1)");
  EXPECT_EQ(atom(in.step(ms(200), kNone)), "stop");
  EXPECT_EQ(atom(in.step(ms(299), kNone)), "stop");
  EXPECT_EQ(atom(in.step(ms(300), kNone)), "ended");

  // One very late step runs out several timers in order.
  Interpreter late(p);
  (void)late.step(ms(0), kNone);
  auto o = late.step(ms(250), kNone);
  EXPECT_EQ(atom(o), "stop");
  EXPECT_EQ(events(o), "timed_out:forward started:turn timed_out:turn started:stop");
}

TEST(Mdl2eInterpreter, NoDurationMeansUnbounded) {
  const Program p = must_compile("plan p { atom forward(1) atom stop }");
  Interpreter in(p);
  for (long long t = 0; t <= 3'600'000; t += 60'000) EXPECT_EQ(atom(in.step(ms(t), kNone)), "forward(1)");
}

TEST(Mdl2eInterpreter, OuterInterruptWinsOverInner) {
  const Program p = must_compile(R"(
interrupt x = external
interrupt y = external
plan p {
  behaviour b until x { atom forward(1) until y  atom turn(1) }
  atom stop
})");
  {
    Interpreter in(p);
    EXPECT_EQ(atom(in.step(ms(0), kNone)), "forward(1)");
    auto o = in.step(ms(10), bits(0b11));  // x and y together: the behaviour ends, not just the atom
    EXPECT_EQ(atom(o), "stop");
    EXPECT_EQ(events(o), "interrupted:b started:stop");
  }
  {
    Interpreter in(p);
    (void)in.step(ms(0), kNone);
    auto o = in.step(ms(10), bits(0b10));  // only y: the atom ends, its sibling runs
    EXPECT_EQ(atom(o), "turn(1)");
    EXPECT_EQ(events(o), "interrupted:forward started:turn");
    o = in.step(ms(20), bits(0b01));
    EXPECT_EQ(atom(o), "stop");
    EXPECT_EQ(events(o), "interrupted:b started:stop");
  }
}

TEST(Mdl2eInterpreter, OuterTimerWinsOverInnerInterrupt) {
  const Program p = must_compile(R"(
interrupt y = external
plan p { behaviour b for 100ms { atom forward(1) until y atom turn(1) } atom stop })");
  Interpreter in(p);
  (void)in.step(ms(0), kNone);
  auto o = in.step(ms(100), bits(1));
  EXPECT_EQ(events(o), "timed_out:b started:stop");
}

TEST(Mdl2eInterpreter, InterruptAlreadyTrueOnEntrySkipsTheComponent) {
  const Program p = must_compile(R"(
sensor ir[2]
interrupt near = ir[1] > 100
plan p { atom forward(1) for 10ms atom turn(1) until near atom stop })");
  Interpreter in(p);
  const std::array<double, 2> close{0, 500};
  (void)in.step(ms(0), {close, 0});
  auto o = in.step(ms(10), {close, 0});
  EXPECT_EQ(events(o), "timed_out:forward started:turn interrupted:turn started:stop");
  EXPECT_EQ(atom(o), "stop");
}

TEST(Mdl2eInterpreter, SensorThresholdsAndMissingSlots) {
  const Program p = must_compile(R"(
sensor a[1]
sensor b[2]
interrupt lt = a[0] < 10
interrupt ge = b[1] >= 5
plan p { atom forward(1) until lt and ge atom stop })");
  Interpreter in(p);
  const std::array<double, 3> v1{5, 0, 4.9};
  const std::array<double, 3> v2{5, 0, 5};
  const std::array<double, 1> short_vec{5};
  EXPECT_EQ(atom(in.step(ms(0), {v1, 0})), "forward(1)");
  EXPECT_EQ(atom(in.step(ms(1), {short_vec, 0})), "forward(1)");  // b[1] missing: false
  EXPECT_EQ(atom(in.step(ms(2), {v2, 0})), "stop");
}

TEST(Mdl2eInterpreter, LoopRepeatsBodyAndLoopNCountsPasses) {
  const Program p = must_compile("plan p loop 2 { atom forward(1) for 10ms atom turn(1) for 10ms }");
  Interpreter in(p);
  const char* expect[] = {"forward(1)", "turn(1)", "forward(1)", "turn(1)", "ended"};
  for (int k = 0; k < 5; ++k) EXPECT_EQ(atom(in.step(ms(10 * k), kNone)), expect[k]) << k;

  const Program q = must_compile("plan q loop for 1s { atom forward(1) for 30ms atom turn(1) for 20ms }");
  Interpreter iq(q);
  for (long long t = 0; t < 1000; t += 5) {
    const char* want = (t % 50) < 30 ? "forward(1)" : "turn(1)";
    ASSERT_EQ(atom(iq.step(ms(t), kNone)), want) << t;
  }
  auto o = iq.step(ms(1000), kNone);
  EXPECT_EQ(events(o), "timed_out:q plan_ended:q");  // the loop's timer runs across passes
}

TEST(Mdl2eInterpreter, PlanEndIsStopForeverAndReportedOnce) {
  const Program p = must_compile("plan p for 1s { atom forward(7) }");
  Interpreter in(p);
  EXPECT_EQ(atom(in.step(ms(0), kNone)), "forward(7)");
  auto o = in.step(ms(1000), kNone);
  EXPECT_FALSE(o.running);
  EXPECT_EQ(events(o), "timed_out:p plan_ended:p");
  EXPECT_DOUBLE_EQ(o.left, 0);
  EXPECT_DOUBLE_EQ(o.right, 0);
  o = in.step(ms(2000), bits(~0ull));
  EXPECT_FALSE(o.running);
  EXPECT_EQ(events(o), "");
  EXPECT_TRUE(in.ended());
  in.reset();
  EXPECT_EQ(atom(in.step(ms(5000), kNone)), "forward(7)");
}

TEST(Mdl2eInterpreter, TaskActionsAreInstantEvents) {
  const Program p = must_compile(R"(
plan p { task start logger atom forward(1) for 10ms task suspend logger task delete camera atom stop })");
  Interpreter in(p);
  auto o = in.step(ms(0), kNone);
  EXPECT_EQ(events(o), "started:p task_action:logger/start started:forward");
  o = in.step(ms(10), kNone);
  EXPECT_EQ(events(o), "timed_out:forward task_action:logger/suspend task_action:camera/delete started:stop");
  EXPECT_EQ(atom(o), "stop");
}

TEST(Mdl2eInterpreter, WorkPerStepIsBounded) {
  const Program p = must_compile("plan p loop 60000 { task start x }");
  Interpreter in(p);
  auto o = in.step(ms(0), kNone);
  ASSERT_GT(o.event_count, 0);
  EXPECT_EQ(o.events[o.event_count - 1].kind, EventKind::kTransitionLimit);
  EXPECT_EQ(o.event_count, 2 + 24 + 1);  // started:p, 4 * nodes + 16 task actions, the limit
  o = in.step(ms(10), kNone);
  EXPECT_EQ(o.events[o.event_count - 1].kind, EventKind::kTransitionLimit);
  EXPECT_TRUE(o.running);
}

TEST(Mdl2eInterpreter, ClockGoingBackwardsIsClamped) {
  const Program p = must_compile("plan p { atom forward(1) for 100ms atom stop }");
  Interpreter in(p);
  (void)in.step(ms(50), kNone);
  EXPECT_EQ(atom(in.step(ms(10), kNone)), "forward(1)");
  EXPECT_EQ(atom(in.step(ms(150), kNone)), "stop");
}

TEST(Mdl2eInterpreter, SameInputsSameOutputs) {
  const Program p = must_compile(R"(
interrupt a = external
interrupt b = external
plan p loop { atom forward(1) until a atom turn(2) for 30ms until b behaviour loop 3 { atom stop for 5ms } })");
  auto run = [&] {
    Interpreter in(p);
    std::string trace;
    std::uint64_t x = 12345;
    for (int k = 0; k < 2000; ++k) {
      x = x * 6364136223846793005ull + 1442695040888963407ull;
      auto o = in.step(ms(k * 3), bits(x >> 62));
      trace += atom(o) + "|" + events(o) + "\n";
    }
    return trace;
  };
  EXPECT_EQ(run(), run());
}

}  // namespace
}  // namespace symb::control::mdl2e
