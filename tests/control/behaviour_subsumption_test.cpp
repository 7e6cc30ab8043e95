// Subsumption layers (wander, avoid, stop_in_zone) in a node under virtual time: scripted sensor
// tasks feed them, a recording task stands for the wheels. Checks suppression through hook
// priority and windows (to the millisecond), inhibition, a layer added, removed and replaced at
// runtime, the layers' own rules, the task types and their parameter errors.
#include <algorithm>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <vector>

#include <gtest/gtest.h>

#include "symb/control/control_task_types.hpp"
#include "symb/control/subsumption/subsumption_layers.hpp"
#include "symb/control/subsumption/subsumption_rewiring.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"

#include "support/virtual_time.hpp"

namespace symb::control {
namespace {

using namespace std::chrono_literals;
using kernel::Time;
using Values = std::vector<float>;

using test_support::ms;

// At each tick, sends what the script says for this instant (nothing when it says nothing).
class SubsumptionSensor : public os::Task {
 public:
  explicit SubsumptionSensor(std::function<std::optional<Values>(Time)> script) : script_(std::move(script)) {}

 protected:
  void on_tick() override {
    if (auto v = script_(now())) send(0, *v);
  }

 private:
  std::function<std::optional<Values>(Time)> script_;
};

struct Command {
  Time time;
  os::TaskId source;
  float left, right;
};

// Keeps every command with its time and sender.
class SubsumptionRecorder : public os::Task {
 public:
  std::vector<Command> commands;

 protected:
  void on_message(const os::Message& m) override {
    ASSERT_EQ(m.numbers().size(), 2u);
    commands.push_back({m.time, m.source, m.numbers()[0], m.numbers()[1]});
  }
};

const Values kNothingNear(7, 0.0f);
Values wall_left() {
  Values v(7, 0.0f);
  v[0] = 3000;
  v[1] = 2500;
  return v;
}

// wander (priority-0 hook) and avoid (priority-1 hook, suppress window) into a recorder.
struct SubsumptionRig {
  kernel::VirtualTimeExecutor ex;
  os::TaskTypeRegistry types;
  os::Node node;
  SubsumptionRecorder* wheels = nullptr;
  os::TaskId ir, wheels_id, wander;

  explicit SubsumptionRig(std::function<std::optional<Values>(Time)> ir_script)
      : node(ex, {.name = "bot", .seed = 7, .types = &types}) {
    EXPECT_TRUE(register_control_task_types(types, {}).ok());
    ir = *node.create("ir", std::make_unique<SubsumptionSensor>(std::move(ir_script)), {.priority = 5, .period = 30ms});
    auto w = std::make_unique<SubsumptionRecorder>();
    wheels = w.get();
    wheels_id = *node.create("wheels", std::move(w), {.queue_capacity = 64});
    wander = make_layer("wander", "wander", {{"speed", "200"}, {"turn_max", "0"}});
    EXPECT_TRUE(node.hook(wander, wheels_id, {.priority = 0}));
  }
  os::TaskId make_layer(std::string_view type, std::string name, std::vector<os::ParamAssignment> params,
                        std::optional<os::TaskOptions> options = std::nullopt) {
    auto id = node.create(type, std::move(name), params, options);
    EXPECT_TRUE(id.ok()) << (id ? "" : id.error());
    return id ? *id : os::TaskId{};
  }
  std::vector<Command> from(os::TaskId source, Time begin, Time end) const {
    std::vector<Command> out;
    for (const auto& c : wheels->commands)
      if (c.source == source && c.time >= begin && c.time < end) out.push_back(c);
    return out;
  }
  std::optional<Time> first_from(os::TaskId source, Time begin) const {
    for (const auto& c : wheels->commands)
      if (c.source == source && c.time >= begin) return c.time;
    return std::nullopt;
  }
};

// A wall on the left from 300 ms to 600 ms inclusive.
std::optional<Values> wall_300_600(Time t) { return (t >= ms(300) && t <= ms(600)) ? wall_left() : kNothingNear; }

TEST(Subsumption, AvoidSuppressesWanderForItsWindowAndReleasesAfterIt) {
  SubsumptionRig rig(wall_300_600);
  const os::TaskId avoid = rig.make_layer("avoid", "avoid", {{"turn", "150"}});
  ASSERT_TRUE(rig.node.hook(rig.ir, avoid));
  ASSERT_TRUE(rig.node.hook(avoid, rig.wheels_id, {.priority = 1, .suppress_window = 100ms}));
  rig.ex.run_until(ms(1000));

  // Before: wander alone, straight on, every 30 ms.
  const auto before = rig.from(rig.wander, ms(0), ms(300));
  ASSERT_EQ(before.size(), 9u);  // 30 .. 270
  for (const auto& c : before) EXPECT_EQ(c.left, 200.0f);
  EXPECT_TRUE(rig.from(avoid, ms(0), ms(300)).empty());
  // While the wall is seen: avoid turns right (wall on the left) at every reading, wander gets
  // nothing through.
  const auto avoiding = rig.from(avoid, ms(0), ms(1000));
  ASSERT_EQ(avoiding.size(), 11u);  // 300 .. 600
  EXPECT_EQ(avoiding.front().time, ms(300));
  EXPECT_EQ(avoiding.back().time, ms(600));
  for (const auto& c : avoiding) {
    EXPECT_EQ(c.left, 150.0f);
    EXPECT_EQ(c.right, -150.0f);
  }
  // Suppressed from avoid's first command at 300 until 100 ms after its last one, 600.
  EXPECT_TRUE(rig.from(rig.wander, ms(300), ms(700)).empty());
  EXPECT_EQ(rig.first_from(rig.wander, ms(300)), ms(720));         // the first wander tick at or after 700
  EXPECT_EQ(rig.from(rig.wander, ms(700), ms(1000)).size(), 10u);  // 720 .. 990
  const auto traffic = rig.node.info(rig.wheels_id)->traffic;
  EXPECT_EQ(traffic.suppressed, 14u);  // wander's ticks 300 .. 690
  EXPECT_EQ(traffic.inhibited, 0u);
}

TEST(Subsumption, WithoutASuppressWindowBothLayersReachTheWheels) {
  SubsumptionRig rig(wall_300_600);
  const os::TaskId avoid = rig.make_layer("avoid", "avoid", {});
  ASSERT_TRUE(rig.node.hook(rig.ir, avoid));
  ASSERT_TRUE(rig.node.hook(avoid, rig.wheels_id, {.priority = 1}));
  rig.ex.run_until(ms(1000));
  EXPECT_EQ(rig.from(rig.wander, ms(300), ms(601)).size(), 11u);
  EXPECT_EQ(rig.node.info(rig.wheels_id)->traffic.suppressed, 0u);
}

TEST(Subsumption, AnExplicitSuppressionFromOutsideBlocksLowerHooksForItsWindow) {
  SubsumptionRig rig([](Time) { return std::nullopt; });
  rig.ex.run_until(ms(100));
  ASSERT_TRUE(rig.node.suppress(rig.wheels_id, 1, 200ms));  // [100, 300)
  rig.ex.run_until(ms(500));
  EXPECT_TRUE(rig.from(rig.wander, ms(100), ms(300)).empty());
  EXPECT_EQ(rig.first_from(rig.wander, ms(100)), ms(300));
}

// Ground readings: in the zone (0.2) from 300 to 450 ms inclusive.
std::optional<Values> zone_300_450(Time t) {
  const float g = (t >= ms(300) && t <= ms(450)) ? 0.2f : 1.0f;
  return Values{g, g};
}

TEST(Subsumption, StopInZoneInhibitsWandersOutputEverywhereForItsWindow) {
  SubsumptionRig rig([](Time) { return std::nullopt; });
  auto second = std::make_unique<SubsumptionRecorder>();  // wander's other listener: inhibition blocks it too
  SubsumptionRecorder* log = second.get();
  const os::TaskId log_id = *rig.node.create("log", std::move(second), {.queue_capacity = 64});
  ASSERT_TRUE(rig.node.hook(rig.wander, log_id));
  const os::TaskId ground =
      *rig.node.create("ground", std::make_unique<SubsumptionSensor>(zone_300_450), {.priority = 5, .period = 30ms});
  const os::TaskId stop = rig.make_layer("stop_in_zone", "stop", {{"inhibit", "wander"}, {"inhibit_for", "100ms"}});
  ASSERT_TRUE(rig.node.hook(ground, stop));
  ASSERT_TRUE(rig.node.hook(stop, rig.wheels_id, {.priority = 2}));  // no suppression: only inhibition
  rig.ex.run_until(ms(800));

  const auto stops = rig.from(stop, ms(0), ms(800));
  ASSERT_EQ(stops.size(), 6u);  // 300 .. 450
  for (const auto& c : stops) {
    EXPECT_EQ(c.left, 0.0f);
    EXPECT_EQ(c.right, 0.0f);
  }
  // Inhibited from 300 until 100 ms after the last stop at 450.
  EXPECT_TRUE(rig.from(rig.wander, ms(300), ms(550)).empty());
  EXPECT_EQ(rig.first_from(rig.wander, ms(300)), ms(570));
  for (const auto& c : log->commands) EXPECT_TRUE(c.time < ms(300) || c.time >= ms(550)) << c.time.count();
  EXPECT_EQ(log->commands.size(), rig.from(rig.wander, ms(0), ms(800)).size());
  EXPECT_EQ(rig.node.info(rig.wheels_id)->traffic.inhibited, 9u);  // wander's ticks 300 .. 540
  EXPECT_EQ(rig.node.info(log_id)->traffic.inhibited, 9u);
  EXPECT_EQ(rig.node.info(rig.wheels_id)->traffic.suppressed, 0u);
}

TEST(Subsumption, StopInZoneLatchesWhenAskedAndIgnoresMalformedReadings) {
  SubsumptionRig rig([](Time) { return std::nullopt; });
  const os::TaskId ground = *rig.node.create(
      "ground", std::make_unique<SubsumptionSensor>([](Time t) -> std::optional<Values> {
        if (t == ms(60)) return Values{0.1f};                                   // wrong count: ignored
        if (t == ms(90)) return Values{std::nanf(""), 0.1f};                    // NaN: ignored
        return Values{t == ms(120) ? 0.1f : 1.0f, t == ms(120) ? 0.3f : 1.0f};  // in the zone at 120 only
      }),
      {.priority = 5, .period = 30ms});
  const os::TaskId stop = rig.make_layer("stop_in_zone", "stop", {{"latch", "true"}, {"zone_max", "0.4"}});
  ASSERT_TRUE(rig.node.hook(ground, stop));
  ASSERT_TRUE(rig.node.hook(stop, rig.wheels_id, {.priority = 2, .suppress_window = 50ms}));
  rig.ex.run_until(ms(600));
  EXPECT_EQ(rig.first_from(stop, ms(0)), ms(120));
  EXPECT_EQ(rig.from(stop, ms(0), ms(600)).size(), 16u);  // 120 .. 570: latched
  EXPECT_TRUE(rig.from(rig.wander, ms(120), ms(600)).empty());
}

TEST(Subsumption, StopInZoneWaitsUntilTheRobotHasBeenInTheZoneForAfter) {
  SubsumptionRig rig([](Time) { return std::nullopt; });
  // In the zone at 300 .. 360, out at 390, in again from 420 on.
  const os::TaskId ground =
      *rig.node.create("ground", std::make_unique<SubsumptionSensor>([](Time t) -> std::optional<Values> {
                         const bool in = (t >= ms(300) && t <= ms(360)) || t >= ms(420);
                         return in ? Values{0.1f, 0.1f} : Values{1.0f, 1.0f};
                       }),
                       {.priority = 5, .period = 30ms});
  const os::TaskId stop = rig.make_layer("stop_in_zone", "stop", {{"after", "100ms"}});
  ASSERT_TRUE(rig.node.hook(ground, stop));
  ASSERT_TRUE(rig.node.hook(stop, rig.wheels_id, {.priority = 2, .suppress_window = 50ms}));
  rig.ex.run_until(ms(700));
  // 300 .. 360 is too short; from 420 the 100 ms have passed at 540.
  EXPECT_EQ(rig.first_from(stop, ms(0)), ms(540));
  EXPECT_EQ(rig.from(stop, ms(0), ms(700)).size(), 6u);     // 540 .. 690
  EXPECT_EQ(rig.first_from(rig.wander, ms(400)), ms(420));  // wander drives on meanwhile
  EXPECT_TRUE(rig.from(rig.wander, ms(540), ms(700)).empty());
}

TEST(Subsumption, LayersAddedRemovedAndReplacedAtRuntime) {
  SubsumptionRig rig(
      [](Time t) -> std::optional<Values> { return t >= ms(300) ? wall_left() : kNothingNear; });  // wall from 300 on
  rig.ex.run_until(ms(150));
  // Added at runtime: avoid, between the IR and the wheels, hook priority 1, window 100 ms.
  const os::TaskId ir[] = {rig.ir};
  auto avoid = add_layer(rig.node, "avoid", "avoid", std::vector<os::ParamAssignment>{{"turn", "150"}}, ir,
                         rig.wheels_id, 1, 100ms);
  ASSERT_TRUE(avoid.ok()) << avoid.error();
  rig.ex.run_until(ms(450));
  EXPECT_EQ(rig.first_from(*avoid, ms(0)), ms(300));
  EXPECT_TRUE(rig.from(rig.wander, ms(300), ms(450)).empty());

  // avoid's commands also leave the node (a hook to a sink, as a DDS bus's remote hook is).
  struct Remote final : os::HookSink {
    Remote() : os::HookSink("dds_to.1") {}
    void on_message(const os::Message& m) override { sources.push_back(m.source); }
    std::vector<os::TaskId> sources;
  };
  auto remote = std::make_shared<Remote>();
  ASSERT_TRUE(rig.node.hook(*avoid, remote).ok());

  // Replaced at runtime by a sharper avoid: it takes over the hooks with their options, the one
  // out of the node included.
  auto sharper = rig.node.create("avoid", "avoid2", std::vector<os::ParamAssignment>{{"turn", "300"}});
  ASSERT_TRUE(sharper.ok());
  ASSERT_TRUE(replace_task(rig.node, *avoid, *sharper).ok());
  int to_remote = 0;
  for (const auto& h : rig.node.hooks()) to_remote += h.sender == *sharper && h.sink == remote;
  EXPECT_EQ(to_remote, 1);
  EXPECT_FALSE(rig.node.info(*avoid).has_value());
  int into = 0, out = 0;
  for (const auto& h : rig.node.hooks()) {
    if (h.receiver == *sharper && h.sender == rig.ir) ++into;
    if (h.sender == *sharper && h.receiver == rig.wheels_id) {
      ++out;
      EXPECT_EQ(h.options.priority, 1);
      EXPECT_EQ(h.options.suppress_window, 100ms);
    }
  }
  EXPECT_EQ(into, 1);
  EXPECT_EQ(out, 1);
  rig.ex.run_until(ms(750));
  const auto turns = rig.from(*sharper, ms(450), ms(750));
  ASSERT_EQ(turns.size(), 9u);  // 480 .. 720: every reading
  for (const auto& c : turns) EXPECT_EQ(c.left, 300.0f);
  EXPECT_TRUE(rig.from(rig.wander, ms(450), ms(750)).empty());  // never a gap for the lower layer
  // The remote end had every command the wheels had, 480 .. 750.
  EXPECT_EQ(std::count(remote->sources.begin(), remote->sources.end(), *sharper), 10);
  EXPECT_EQ(rig.from(*sharper, ms(450), ms(751)).size(), 10u);

  // Removed at runtime (after its reading at 750): wander drives again once that last window,
  // [750, 850), has passed.
  ASSERT_TRUE(rig.node.remove(*sharper).ok());
  rig.ex.run_until(ms(1000));
  EXPECT_TRUE(rig.from(rig.wander, ms(750), ms(850)).empty());
  EXPECT_EQ(rig.first_from(rig.wander, ms(750)), ms(870));
  EXPECT_EQ(rig.from(rig.wander, ms(850), ms(1000)).size(), 5u);  // 870 .. 990

  // replace_task refuses nonsense without touching anything.
  EXPECT_FALSE(replace_task(rig.node, rig.wander, rig.wander).ok());
  EXPECT_FALSE(replace_task(rig.node, *sharper, rig.wander).ok());
  EXPECT_TRUE(rig.node.info(rig.wander).has_value());
}

TEST(Subsumption, AvoidKeepsItsDirectionThroughAnEpisodeAndHoldsAfterIt) {
  // Wall on the left first, then only in the centre, then on the right, then clear from 300.
  SubsumptionRig rig([](Time t) -> std::optional<Values> {
    Values v(7, 0.0f);
    if (t < ms(100)) {
      v[0] = 3000;
    } else if (t < ms(200)) {
      v[2] = 3000;
    } else if (t < ms(300)) {
      v[4] = 3000;
    }
    return v;
  });
  const os::TaskId avoid = rig.make_layer("avoid", "avoid", {{"turn", "100"}, {"forward", "20"}, {"hold", "90ms"}});
  ASSERT_TRUE(rig.node.hook(rig.ir, avoid));
  ASSERT_TRUE(rig.node.hook(avoid, rig.wheels_id, {.priority = 1, .suppress_window = 40ms}));
  rig.ex.run_until(ms(600));
  const auto cmds = rig.from(avoid, ms(0), ms(600));
  ASSERT_FALSE(cmds.empty());
  // The episode runs from 30 (the first reading) to 270 + 90 hold = 360 inclusive... of readings
  // below 360: 30 .. 330 (330 - 270 = 60 < 90); at 360 the hold has passed.
  EXPECT_EQ(cmds.front().time, ms(30));
  EXPECT_EQ(cmds.back().time, ms(330));
  for (const auto& c : cmds) {
    EXPECT_EQ(c.left, 120.0f);  // forward + turn: turning right, as decided at the start
    EXPECT_EQ(c.right, -80.0f);
  }
}

TEST(Subsumption, WanderTurnsAtRandomFromItsOwnStreamReproducibly) {
  auto run = [](std::uint64_t seed) {
    kernel::VirtualTimeExecutor ex;
    os::TaskTypeRegistry types;
    EXPECT_TRUE(register_control_task_types(types, {}).ok());
    os::Node node(ex, {.name = "bot", .seed = seed, .types = &types});
    auto rec = std::make_unique<SubsumptionRecorder>();
    SubsumptionRecorder* r = rec.get();
    const auto wheels = *node.create("wheels", std::move(rec), {.queue_capacity = 512});
    const auto w = *node.create("wander", "wander",
                                std::vector<os::ParamAssignment>{{"turn_max", "80"}, {"change_every", "300ms"}});
    EXPECT_TRUE(node.hook(w, wheels));
    ex.run_until(ms(3000));
    return r->commands;
  };
  const auto a = run(1), b = run(1), c = run(2);
  ASSERT_EQ(a.size(), 100u);
  ASSERT_EQ(a.size(), b.size());
  std::map<float, int> turns;
  bool differs = false;
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].left, b[k].left);
    EXPECT_EQ(a[k].left + a[k].right, 400.0f);  // speed 200 on average
    EXPECT_LE(std::abs(a[k].right - a[k].left), 160.0f);
    ++turns[a[k].right - a[k].left];
    if (a[k].left != c[k].left) differs = true;
  }
  EXPECT_GE(turns.size(), 6u);  // about 10 changes in 3 s
  EXPECT_TRUE(differs);
}

TEST(Subsumption, LayersProbeActivityAndOutput) {
  SubsumptionRig rig(wall_300_600);
  std::vector<std::pair<std::string, Values>> samples;
  rig.node.set_probe_sink([&](const os::ProbeSample& s) {
    if (s.task == "avoid") samples.push_back({std::string(s.channel), Values(s.values.begin(), s.values.end())});
  });
  const os::TaskId avoid = rig.make_layer("avoid", "avoid", {{"turn", "150"}});
  ASSERT_TRUE(rig.node.hook(rig.ir, avoid));
  rig.ex.run_until(ms(330));
  ASSERT_EQ(samples.size(), 22u);  // 11 readings x (active, output)
  EXPECT_EQ(samples[0], (std::pair<std::string, Values>{"active", {0.0f}}));
  EXPECT_EQ(samples[1], (std::pair<std::string, Values>{"output", {0.0f, 0.0f}}));
  EXPECT_EQ(samples[18], (std::pair<std::string, Values>{"active", {1.0f}}));
  EXPECT_EQ(samples[19], (std::pair<std::string, Values>{"output", {150.0f, -150.0f}}));
}

TEST(Subsumption, BadParametersAreRejectedWithTheirName) {
  kernel::VirtualTimeExecutor ex;
  os::TaskTypeRegistry types;
  ASSERT_TRUE(register_control_task_types(types, {}).ok());
  os::Node node(ex, {.name = "bot", .types = &types});
  auto create = [&](std::string_view type, std::vector<os::ParamAssignment> p) {
    auto r = node.create(type, "t", p);
    return r ? std::string() : r.error();
  };
  EXPECT_NE(create("wander", {{"speed", "900"}}).find("speed"), std::string::npos);
  EXPECT_NE(create("avoid", {{"threshold", "x"}}).find("threshold"), std::string::npos);
  EXPECT_NE(create("stop_in_zone", {{"zone_min", "0.8"}, {"zone_max", "0.2"}}).find("zone_min must not exceed"),
            std::string::npos);
  EXPECT_NE(create("stop_in_zone", {{"inhibit", "no good"}}).find("inhibit"), std::string::npos);
  EXPECT_NE(create("avoid", {{"trun", "1"}}).find("turn"), std::string::npos);  // did you mean
  // Runtime changes go through the same schema.
  auto w = node.create("wander", "w", std::vector<os::ParamAssignment>{});
  ASSERT_TRUE(w.ok());
  EXPECT_TRUE(node.set_parameter(*w, "speed", "120").ok());
  EXPECT_FALSE(node.set_parameter(*w, "speed", "-900").ok());
}

}  // namespace
}  // namespace symb::control
