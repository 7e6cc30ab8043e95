// The arbiter task (paper VI-C, multiple controllers): its predicted step fitness, and switching
// on a plain node with stand-in variants that send fixed commands: the first heard drives, a
// better one takes over only past the margin and the dwell, a silent driver is handed over at
// once, bad messages are ignored and nothing non-finite reaches the wheels.
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "symb/evo/arbiter/arbiter_task.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"

namespace symb::evo {
namespace {

using namespace std::chrono_literals;

const std::vector<float> kOpen = {0, 0, 0, 0, 0, 0, 0};
const std::vector<float> kWallLeft = {4000, 3500, 500, 0, 0, 0, 0};
const std::vector<float> kWallAhead = {1000, 2000, 4400, 2000, 1000, 0, 0};

TEST(ArbiterScore, OpenSpaceRewardsFastStraightDriving) {
  const ArbiterOptions o;
  EXPECT_NEAR(predicted_step_fitness(kOpen, 500, 500, o), 1.0, 1e-9);
  EXPECT_NEAR(predicted_step_fitness(kOpen, 0, 0, o), 0.0, 1e-9);
  EXPECT_LT(predicted_step_fitness(kOpen, 500, -500, o), 0.01);  // spinning in place
  EXPECT_LT(predicted_step_fitness(kOpen, 300, 200, o), predicted_step_fitness(kOpen, 300, 300, o));
  EXPECT_EQ(predicted_step_fitness(kOpen, -500, -500, o), 0.0);  // reversing earns nothing
}

TEST(ArbiterScore, NearAWallTurningAwayBeatsTurningTowardsOrAdvancing) {
  const ArbiterOptions o;
  const double away = predicted_step_fitness(kWallLeft, 300, -300, o);     // clockwise: away from the left
  const double towards = predicted_step_fitness(kWallLeft, -300, 300, o);  // into it
  const double straight = predicted_step_fitness(kWallLeft, 500, 500, o);
  EXPECT_GT(away, 0.3);
  EXPECT_LT(towards, -0.3);
  EXPECT_LT(straight, 0.0);
  // A wall ahead may be left either way.
  EXPECT_NEAR(predicted_step_fitness(kWallAhead, 300, -300, o), predicted_step_fitness(kWallAhead, -300, 300, o), 1e-9);
  EXPECT_EQ(predicted_step_fitness(kWallLeft, std::nan(""), 0, o), -1.0);
  EXPECT_EQ(predicted_step_fitness(std::vector<float>{1, 2}, 0, 0, o), -1.0);
}

// Sends readings every 30 ms: open space, with a wall on the left every `wall_every`-th step.
class Ir final : public os::Task {
 public:
  int wall_every = 4;

 protected:
  void on_tick() override { send(0, (++step_ % wall_every == 0) ? kWallLeft : kOpen); }

 private:
  int step_ = 0;
};

// A variant that answers every reading with a command computed by `rule`.
class Variant final : public os::Task {
 public:
  explicit Variant(std::function<std::vector<float>(std::span<const float>)> rule) : rule_(std::move(rule)) {}

 protected:
  void on_message(const os::Message& m) override { send(0, rule_(m.numbers())); }

 private:
  std::function<std::vector<float>(std::span<const float>)> rule_;
};

class ArbiterWheels final : public os::Task {
 public:
  std::vector<std::pair<os::TaskId, std::vector<float>>> seen;  // not the source: the arbiter forwards
  std::size_t non_finite = 0;

 protected:
  void on_message(const os::Message& m) override {
    for (float v : m.numbers())
      if (!std::isfinite(v) || std::abs(v) > 500) ++non_finite;
    seen.push_back({m.source, {m.numbers().begin(), m.numbers().end()}});
  }
};

bool wall_left(std::span<const float> ir) { return ir.size() == 7 && ir[0] > 1000; }

struct Bench {
  kernel::VirtualTimeExecutor executor;
  std::unique_ptr<os::Node> node = std::make_unique<os::Node>(executor, os::NodeConfig{.name = "bench"});
  os::TaskId ir, judge, wheels_id;
  ArbiterTask* arbiter = nullptr;
  ArbiterWheels* wheels = nullptr;

  explicit Bench(ArbiterOptions options) {
    ir = *node->create("ir", std::make_unique<Ir>(), {.priority = 3, .period = 30ms});
    auto a = std::make_unique<ArbiterTask>(options);
    arbiter = a.get();
    judge = *node->create("judge", std::move(a), {.priority = 1, .queue_capacity = 32});
    auto w = std::make_unique<ArbiterWheels>();
    wheels = w.get();
    wheels_id = *node->create("wheels", std::move(w), {.queue_capacity = 32});
    EXPECT_TRUE(node->hook(ir, judge).ok());
    EXPECT_TRUE(node->hook(judge, wheels_id).ok());
  }
  ~Bench() { node->clear(); }
  os::TaskId add(const char* name, std::function<std::vector<float>(std::span<const float>)> rule, int priority) {
    const auto id = *node->create(name, std::make_unique<Variant>(std::move(rule)), {.priority = priority});
    EXPECT_TRUE(node->hook(ir, id).ok());
    EXPECT_TRUE(node->hook(id, judge).ok());
    return id;
  }
};

std::vector<float> good(std::span<const float> ir) {
  return wall_left(ir) ? std::vector<float>{300, -300} : std::vector<float>{400, 400};
}
std::vector<float> bad(std::span<const float> ir) {
  return wall_left(ir) ? std::vector<float>{-300, 300} : std::vector<float>{400, 400};
}

TEST(ArbiterTask, ABetterVariantTakesOverAfterTheDwellAndStays) {
  ArbiterOptions o;
  o.dwell = 2s;
  Bench b(o);
  const os::TaskId worse = b.add("bad", bad, 2);  // higher priority: heard first
  const os::TaskId better = b.add("good", good, 1);
  b.executor.run_for(1s);
  EXPECT_EQ(b.arbiter->stats().active, worse);  // the first heard drives; the dwell holds
  b.executor.run_for(3s);
  ArbiterStats s = b.arbiter->stats();
  EXPECT_EQ(s.active, better);
  EXPECT_EQ(s.switches, 1u);
  ASSERT_EQ(s.variants.size(), 2u);
  EXPECT_GT(s.variants[1].average, s.variants[0].average + o.margin);
  b.executor.run_for(20s);
  s = b.arbiter->stats();
  EXPECT_EQ(s.active, better);
  EXPECT_EQ(s.switches, 1u);
  EXPECT_GT(s.forwarded, 700u);  // one command a step: 24 s / 30 ms = 800
  EXPECT_EQ(b.wheels->non_finite, 0u);
  // The wheels now get the good variant's answer to a wall on the left.
  EXPECT_EQ(b.wheels->seen.back().first, b.judge);
}

TEST(ArbiterTask, EqualVariantsDoNotFlapInsideTheMargin) {
  Bench b(ArbiterOptions{});
  const os::TaskId first = b.add("a", good, 2);
  b.add(
      "b",
      [](std::span<const float> ir) {
        auto c = good(ir);
        c[0] *= 0.98f, c[1] *= 0.98f;  // a hair slower: within the margin
        return c;
      },
      1);
  b.executor.run_for(60s);
  EXPECT_EQ(b.arbiter->stats().active, first);
  EXPECT_EQ(b.arbiter->stats().switches, 0u);
}

TEST(ArbiterTask, ARemovedDriverIsHandedOverAtOnce) {
  Bench b(ArbiterOptions{});
  const os::TaskId driver = b.add("good", good, 2);
  const os::TaskId other = b.add("other", bad, 1);
  b.executor.run_for(5s);
  ASSERT_EQ(b.arbiter->stats().active, driver);
  ASSERT_TRUE(b.node->remove(driver).ok());
  const std::size_t before = b.wheels->seen.size();
  b.executor.run_for(300ms);
  const ArbiterStats s = b.arbiter->stats();
  EXPECT_EQ(s.active, other);
  EXPECT_EQ(s.dropped, 1u);
  EXPECT_EQ(s.variants.size(), 1u);
  EXPECT_GE(b.wheels->seen.size(), before + 4);  // the wheels are fed again within the stale time
  // With every variant gone the arbiter sends nothing (the wheels' watchdog stops the robot).
  ASSERT_TRUE(b.node->remove(other).ok());
  b.executor.run_for(300ms);
  EXPECT_FALSE(b.arbiter->stats().active.has_value());
  const std::size_t after = b.wheels->seen.size();
  b.executor.run_for(1s);
  EXPECT_EQ(b.wheels->seen.size(), after);
}

TEST(ArbiterTask, BadMessagesAreIgnoredAndNothingNonFiniteIsForwarded) {
  Bench b(ArbiterOptions{});
  const float nan = std::numeric_limits<float>::quiet_NaN();
  b.add(
      "broken",
      [nan](std::span<const float>) {
        return std::vector<float>{nan, 9999};
      },
      2);
  b.add(
      "loud",
      [](std::span<const float>) {
        return std::vector<float>{9999, 9999};
      },
      1);
  os::Message wrong_port;
  wrong_port.port = 1;
  wrong_port.payload = os::Payload({1.f, 2.f});
  ASSERT_TRUE(b.node->post(b.judge, wrong_port).ok());
  os::Message one_number;
  one_number.payload = os::Payload({1.f});
  ASSERT_TRUE(b.node->post(b.judge, one_number).ok());
  b.executor.run_for(5s);
  const ArbiterStats s = b.arbiter->stats();
  EXPECT_GE(s.ignored, 2u);
  EXPECT_EQ(b.wheels->non_finite, 0u);
  EXPECT_FALSE(b.wheels->seen.empty());  // the loud one (clamped to 500) took over from the broken one
  ASSERT_EQ(s.variants.size(), 2u);
  EXPECT_NEAR(s.variants[0].average, -1.0, 1e-9);
}

TEST(ArbiterTask, TypeIsRegisteredWithItsSchema) {
  os::TaskTypeRegistry registry;
  ASSERT_TRUE(register_arbiter_task_type(registry).ok());
  const os::TaskType* t = registry.find("arbiter");
  ASSERT_NE(t, nullptr);
  const std::vector<os::ParamAssignment> bad_margin = {{"margin", "5", 1}};
  EXPECT_FALSE(registry.resolve(*t, bad_margin).ok());
  auto p = registry.resolve(*t, {});
  ASSERT_TRUE(p.ok());
  auto made = t->make(*p);
  ASSERT_TRUE(made) << made.error();
  EXPECT_NE(made.value(), nullptr);
}

}  // namespace
}  // namespace symb::evo
