// The fitness formulas (fitness.hpp) against values computed by hand, and the `fitness` task in a
// node: classification by vector length, one step per IR reading with the latest command, the
// [sum, steps, step] output, reset, a stale command, bad messages.
#include "symb/evo/fitness/fitness.hpp"

#include <cmath>
#include <memory>
#include <mutex>
#include <vector>

#include <gtest/gtest.h>

#include "symb/evo/evo_task_types.hpp"
#include "symb/evo/fitness/fitness_task.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/robot/ports.hpp"

namespace symb::evo {
namespace {

using namespace std::chrono_literals;

TEST(FitnessFormula, Normalisation) {
  EXPECT_DOUBLE_EQ(normalised_wheel(250), 0.5);
  EXPECT_DOUBLE_EQ(normalised_wheel(-500), -1.0);
  EXPECT_DOUBLE_EQ(normalised_wheel(900), 1.0);  // clamped
  EXPECT_DOUBLE_EQ(normalised_wheel(std::nan("")), 0.0);
  const std::vector<float> ir{0, 901, 450.5f, 0, 0, 0, 0};
  EXPECT_NEAR(highest_ir_activation(ir), 0.2, 1e-7);
  EXPECT_DOUBLE_EQ(highest_ir_activation(std::vector<float>{9000, 0, 0}), 1.0);
  EXPECT_DOUBLE_EQ(highest_ir_activation(std::vector<float>{-5, 0, 0}), 0.0);
  EXPECT_DOUBLE_EQ(highest_ir_activation(std::vector<float>{0, std::nanf(""), 0}), 1.0);  // as touching
  EXPECT_DOUBLE_EQ(highest_ir_activation({}), 0.0);
}

TEST(FitnessFormula, FloreanoMondadaByHand) {
  // V = (0.5 + 0.3) / 2 = 0.4; dv = 0.2 / 2 = 0.1; 0.4 (1 - sqrt 0.1) (1 - 0.2) = 0.218807...
  EXPECT_NEAR(floreano_mondada(0.5, 0.3, 0.2), 0.4 * (1 - 0.31622776601683794) * 0.8, 1e-12);
  EXPECT_NEAR(floreano_mondada(0.5, 0.3, 0.2), 0.2188071150, 1e-9);
  EXPECT_DOUBLE_EQ(floreano_mondada(1, 1, 0), 1.0);
  EXPECT_DOUBLE_EQ(floreano_mondada(1, -1, 0), 0.0);   // spinning on the spot: dv = 1
  EXPECT_DOUBLE_EQ(floreano_mondada(-1, -1, 0), 1.0);  // V is the mean ABSOLUTE speed
  EXPECT_DOUBLE_EQ(floreano_mondada(1, 1, 1), 0.0);    // touching
  EXPECT_NEAR(floreano_mondada(-0.4, 0.2, 0.5), 0.3 * (1 - std::sqrt(0.3)) * 0.5, 1e-12);
}

TEST(FitnessFormula, OnePlusOneNolfiByHand) {
  // translation (0.5 + 0.3) / 2 = 0.4, rotation 0.1, d_min 0.8: 0.4 x 0.9 x 0.8
  EXPECT_NEAR(one_plus_one_step(0.5, 0.3, 0.2), 0.288, 1e-12);
  EXPECT_DOUBLE_EQ(one_plus_one_step(1, 1, 0), 1.0);
  EXPECT_DOUBLE_EQ(one_plus_one_step(1, -1, 0), 0.0);   // no translation
  EXPECT_DOUBLE_EQ(one_plus_one_step(-1, -1, 0), 1.0);  // |v_t|
  EXPECT_NEAR(one_plus_one_step(1, 0, 0.5), 0.5 * 0.5 * 0.5, 1e-12);
}

TEST(FitnessFormula, LioLibByHand) {
  // v_t = min(0.5, 0.3) = 0.3, v_rot = 0.2, s_min = 0.8: 0.3 x 0.8 x 0.8
  EXPECT_NEAR(liolib_step(0.5, 0.3, 0.2), 0.192, 1e-12);
  // a fast spin is punished: 0.8 (1 - 1.6) x 1
  EXPECT_NEAR(liolib_step(0.8, -0.8, 0), -0.48, 1e-12);
  // touching (s_min = 0.05 <= 0.1): only the floor term 0.01 s_min
  EXPECT_NEAR(liolib_step(1, 1, 0.95), 0.0005, 1e-12);
  EXPECT_NEAR(liolib_step(1, 1, 0.9), 0.001, 1e-12);  // s_min = 0.1 is touching
  EXPECT_NEAR(liolib_step(1, 1, 0.85), 0.15, 1e-12);  // s_min = 0.15 is not
}

TEST(FitnessFormula, FromRawValuesAndNames) {
  const std::vector<float> ir{0, 901, 0, 0, 0, 0, 0};  // i = 0.2
  EXPECT_NEAR(fitness_step(FitnessFormula::kOnePlusOne, 250, 150, ir), 0.288, 1e-6);
  EXPECT_NEAR(fitness_step(FitnessFormula::kFloreanoMondada, 250, 150, ir), 0.2188071150, 1e-6);
  EXPECT_NEAR(fitness_step(FitnessFormula::kLioLib, 250, 150, ir), 0.192, 1e-6);
  for (auto f : {FitnessFormula::kFloreanoMondada, FitnessFormula::kOnePlusOne, FitnessFormula::kLioLib})
    EXPECT_EQ(parse_fitness_formula(to_string(f)), f);
  EXPECT_FALSE(parse_fitness_formula("nolfi").has_value());
}

// Keeps what it is sent.
class Recorder : public os::Task {
 public:
  std::vector<std::vector<float>> values() const {
    std::lock_guard lock(mu_);
    return values_;
  }

 protected:
  void on_message(const os::Message& m) override {
    std::lock_guard lock(mu_);
    values_.emplace_back(m.numbers().begin(), m.numbers().end());
  }

 private:
  mutable std::mutex mu_;
  std::vector<std::vector<float>> values_;
};

struct FitnessRig {
  kernel::VirtualTimeExecutor ex;
  os::TaskTypeRegistry registry;
  std::unique_ptr<os::Node> node;
  os::TaskId fitness, rec_id;
  Recorder* rec = nullptr;
  FitnessTask* task = nullptr;

  explicit FitnessRig(std::string_view params) {
    EXPECT_TRUE(register_evo_task_types(registry, {}).ok());
    node = std::make_unique<os::Node>(ex, os::NodeConfig{.name = "bot", .types = &registry});
    auto a = os::parse_param_assignments(params);
    EXPECT_TRUE(a.ok());
    auto id = node->create("fitness", "fitness", *a);
    EXPECT_TRUE(id.ok()) << (id ? "" : id.error());
    fitness = *id;
    auto r = std::make_unique<Recorder>();
    rec = r.get();
    rec_id = *node->create("rec", std::move(r), {.queue_capacity = 64});
    EXPECT_TRUE(node->hook(fitness, rec_id).ok());
  }
  void post(std::vector<float> v, os::Port port = 0) {
    os::Message m;
    m.port = port;
    m.payload.assign(v);
    EXPECT_TRUE(node->post(fitness, m).ok());
    ex.run_for(1ms);
  }
};

TEST(FitnessTask, OneStepPerReadingWithTheLatestCommand) {
  FitnessRig rig("formula=one_plus_one");
  rig.post({0, 0, 0, 0, 0, 0, 0});  // no command yet: wheels count as stopped
  rig.post({250, 150});             // a command: no step
  rig.post({0, 901, 0, 0, 0, 0, 0});
  rig.post({500, 500});
  rig.post({500, 500});  // only the latest counts
  rig.post({0, 0, 0, 0, 0, 0, 0});
  const auto out = rig.rec->values();
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[0], (std::vector<float>{0, 1, 0}));
  EXPECT_NEAR(out[1][0], 0.288, 1e-6);
  EXPECT_EQ(out[1][1], 2);
  EXPECT_NEAR(out[1][2], 0.288, 1e-6);
  EXPECT_NEAR(out[2][0], 1.288, 1e-6);
  EXPECT_EQ(out[2][1], 3);
  EXPECT_NEAR(out[2][2], 1.0, 1e-6);
}

// every=N: one report per N readings, [sum, steps, window sum, N]; the sum and step count are the
// same as at every=1, and changing `every` at runtime takes effect at the next report.
TEST(FitnessTask, EveryNthStepReportsTheWindowSinceTheLast) {
  FitnessRig rig("formula=one_plus_one every=3");
  rig.post({500, 500});
  for (int i = 0; i < 7; ++i) rig.post({0, 0, 0, 0, 0, 0, 0});  // 1 per step: straight, nothing seen
  auto out = rig.rec->values();
  ASSERT_EQ(out.size(), 2u);  // after readings 3 and 6
  EXPECT_EQ(out[0], (std::vector<float>{3, 3, 3, 3}));
  EXPECT_EQ(out[1], (std::vector<float>{6, 6, 3, 3}));
  ASSERT_TRUE(rig.node->set_parameter(rig.fitness, "every", "1").ok());
  rig.ex.run_for(1ms);
  rig.post({0, 0, 0, 0, 0, 0, 0});  // the 8th reading: the open window (7, 8) goes out whole
  rig.post({0, 0, 0, 0, 0, 0, 0});  // then one per step again
  out = rig.rec->values();
  ASSERT_EQ(out.size(), 4u);
  EXPECT_EQ(out[2], (std::vector<float>{8, 8, 2, 2}));
  EXPECT_EQ(out[3], (std::vector<float>{9, 9, 1}));
  EXPECT_FALSE(rig.node->set_parameter(rig.fitness, "every", "0").ok());
}

TEST(FitnessTask, EachFormulaByName) {
  for (const char* f : {"floreano_mondada", "one_plus_one", "liolib"}) {
    SCOPED_TRACE(f);
    FitnessRig rig(std::string("formula=") + f);
    rig.post({250, 150});
    rig.post({0, 901, 0, 0, 0, 0, 0});
    const auto out = rig.rec->values();
    ASSERT_EQ(out.size(), 1u);
    EXPECT_NEAR(out[0][2], fitness_step(*parse_fitness_formula(f), 250, 150, std::vector<float>{0, 901, 0}), 1e-6);
  }
}

TEST(FitnessTask, ResetZeroesTheSum) {
  FitnessRig rig("");
  rig.post({500, 500});
  rig.post({0, 0, 0, 0, 0, 0, 0});
  rig.post({0, 0, 0, 0, 0, 0, 0});
  ASSERT_TRUE(rig.node->set_parameter(rig.fitness, "reset", "true").ok());
  rig.ex.run_for(1ms);
  rig.post({500, 500});
  rig.post({0, 0, 0, 0, 0, 0, 0});
  const auto out = rig.rec->values();
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[1], (std::vector<float>{2, 2, 1}));
  EXPECT_EQ(out[2], (std::vector<float>{1, 1, 1}));  // counted from zero again
}

TEST(FitnessTask, FormulaChangesAtRuntimeAndABadOneIsIgnored) {
  FitnessRig rig("formula=one_plus_one");
  ASSERT_TRUE(rig.node->set_parameter(rig.fitness, "formula", "nolfi").ok());  // checked by the task
  rig.ex.run_for(1ms);
  rig.post({250, 150});
  rig.post({0, 901, 0, 0, 0, 0, 0});
  ASSERT_TRUE(rig.node->set_parameter(rig.fitness, "formula", "liolib").ok());
  rig.ex.run_for(1ms);
  rig.post({0, 901, 0, 0, 0, 0, 0});
  const auto out = rig.rec->values();
  ASSERT_EQ(out.size(), 2u);
  EXPECT_NEAR(out[0][2], 0.288, 1e-6);  // still one_plus_one
  EXPECT_NEAR(out[1][2], 0.192, 1e-6);  // liolib from the next step
}

TEST(FitnessTask, AStaleCommandCountsAsStoppedWheels) {
  FitnessRig rig("command_timeout=50ms");
  rig.post({500, 500});
  rig.ex.run_for(100ms);  // the wheels' watchdog would have stopped the robot by now
  rig.post({0, 0, 0, 0, 0, 0, 0});
  const auto out = rig.rec->values();
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0], (std::vector<float>{0, 1, 0}));
}

TEST(FitnessTask, BadMessagesAreIgnored) {
  FitnessRig rig("");
  rig.post({500, 500});
  rig.post({7});                       // one number: neither
  rig.post({0, 0, 0, 0, 0, 0, 0}, 1);  // another port
  rig.post({std::nanf(""), 500});      // a NaN speed counts as 0
  rig.post({0, 0, 0, 0, 0, 0, 0});
  const auto out = rig.rec->values();
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0][1], 1);
  EXPECT_TRUE(std::isfinite(out[0][0]));
  EXPECT_NEAR(out[0][2], 0.5 * (1 - 0.5), 1e-6);  // translation 0.5, rotation 0.5
}

TEST(FitnessTask, BadParametersAreRefusedAtCreation) {
  os::TaskTypeRegistry registry;
  ASSERT_TRUE(register_evo_task_types(registry, {}).ok());
  kernel::VirtualTimeExecutor ex;
  os::Node node(ex, os::NodeConfig{.name = "bot", .types = &registry});
  const std::vector<os::ParamAssignment> bad{{"formula", "nolfi", 1}};
  auto id = node.create("fitness", "f", bad);
  ASSERT_FALSE(id.ok());
  EXPECT_NE(id.error().find("nolfi"), std::string::npos) << id.error();
}

// The fitness report has a layout of its own: hooking it into a task that reads wheel commands is
// refused at hook time, naming both ends.
TEST(FitnessTaskOnNode, ItsReportIntoTheWheelsIsRefused) {
  FitnessRig rig("formula=one_plus_one");
  os::TaskOptions o;
  o.ports = os::PortDeclaration{{{0, "wheels", robot::layout::kWheelCommand}}, {}};
  auto wheels = rig.node->create("wheels", std::make_unique<Recorder>(), o);
  ASSERT_TRUE(wheels.ok()) << wheels.error();
  auto h = rig.node->hook(rig.fitness, *wheels);
  ASSERT_FALSE(h.ok());
  EXPECT_NE(h.error().find("fitness-report"), std::string::npos) << h.error();
  EXPECT_NE(h.error().find("wheels"), std::string::npos) << h.error();
}

}  // namespace
}  // namespace symb::evo
