#include "symb/os/task_type_registry.hpp"

#include <gtest/gtest.h>

#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"

namespace symb::os {
namespace {

using namespace std::chrono_literals;

// Remembers its parameters, and accepts runtime changes of "gain" only.
class GainTask : public Task {
 public:
  explicit GainTask(const ParamSet& p) : gain(p.real("gain")) {}
  double gain;

 protected:
  kernel::Status on_parameter(std::string_view name, const ParamValue& v) override {
    if (name != "gain") return Task::on_parameter(name, v);
    gain = std::get<double>(v);
    return {};
  }
};

TaskType gain_type() {
  TaskType t;
  t.name = "gain";
  t.doc = "multiplies";
  t.params = {{"gain", ParamType::kReal, 1.0, 0.0, 10.0, "factor"},
              {"label", ParamType::kString, std::string("g"), 1.0, 16.0, "a label"}};
  t.defaults.period = 10ms;
  t.make = [](const ParamSet& p) { return std::make_unique<GainTask>(p); };
  return t;
}

TEST(TaskTypeRegistry, RejectsBadTypes) {
  TaskTypeRegistry reg;
  ASSERT_TRUE(reg.add(gain_type()));
  EXPECT_FALSE(reg.add(gain_type()));  // duplicate
  TaskType bad = gain_type();
  bad.name = "9bad";
  EXPECT_FALSE(reg.add(bad));
  bad = gain_type();
  bad.name = "nofactory";
  bad.make = nullptr;
  EXPECT_FALSE(reg.add(bad));
  bad = gain_type();
  bad.name = "baddefault";
  bad.params[0].default_value = 11.0;
  auto st = reg.add(bad);
  ASSERT_FALSE(st);
  EXPECT_NE(st.error().find("default"), std::string::npos);
  bad = gain_type();
  bad.name = "twice";
  bad.params.push_back(bad.params[0]);
  EXPECT_FALSE(reg.add(bad));
  EXPECT_EQ(reg.list().size(), 1u);
}

TEST(TaskTypeRegistry, ResolveAppliesDefaultsAndOverrides) {
  TaskTypeRegistry reg;
  ASSERT_TRUE(reg.add(gain_type()));
  const TaskType* t = reg.find("gain");
  ASSERT_NE(t, nullptr);
  auto given = *parse_param_assignments("gain=2.5");
  auto set = reg.resolve(*t, given);
  ASSERT_TRUE(set) << set.error();
  EXPECT_EQ(set->real("gain"), 2.5);
  EXPECT_EQ(set->string("label"), "g");
}

TEST(TaskTypeRegistry, ResolveErrorsNameTheProblem) {
  TaskTypeRegistry reg;
  ASSERT_TRUE(reg.add(gain_type()));
  const TaskType& t = *reg.find("gain");
  auto unknown = reg.resolve(t, *parse_param_assignments("gian=1"));
  ASSERT_FALSE(unknown);
  EXPECT_NE(unknown.error().find("did you mean 'gain'"), std::string::npos) << unknown.error();
  auto twice = reg.resolve(t, *parse_param_assignments("gain=1 gain=2"));
  ASSERT_FALSE(twice);
  EXPECT_NE(twice.error().find("column 8"), std::string::npos) << twice.error();
  EXPECT_FALSE(reg.resolve(t, *parse_param_assignments("gain=20")));
  EXPECT_NE(reg.unknown_type_error("gainn").find("did you mean 'gain'"), std::string::npos);
}

TEST(TaskTypeRegistry, NodeCreatesByNameAndChangesParametersAtRuntime) {
  TaskTypeRegistry reg;
  ASSERT_TRUE(reg.add(gain_type()));
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"n", 1, 64, &reg});
  auto id = node.create("gain", "g1", *parse_param_assignments("gain=3"));
  ASSERT_TRUE(id) << id.error();
  auto info = node.info(*id);
  ASSERT_TRUE(info);
  EXPECT_EQ(info->type, "gain");
  EXPECT_EQ(info->period, kernel::Duration{10ms});  // the type's default options
  EXPECT_EQ(node.parameters(*id)->real("gain"), 3.0);

  ASSERT_TRUE(node.set_parameter(*id, "gain", "4.5"));
  ex.run_for(1ms);
  EXPECT_EQ(node.parameters(*id)->real("gain"), 4.5);

  // Passes the schema but the task refuses: logged, value unchanged.
  ASSERT_TRUE(node.set_parameter(*id, "label", "other"));
  ex.run_for(1ms);
  EXPECT_EQ(node.parameters(*id)->string("label"), "g");
  EXPECT_NE(node.log().since(0).back().text.find("not changed"), std::string::npos);

  EXPECT_FALSE(node.set_parameter(*id, "gain", "11"));
  EXPECT_FALSE(node.set_parameter(*id, "gian", "1"));
  EXPECT_FALSE(node.create("nosuch", "x", {}));
  EXPECT_FALSE(node.create("gain", "g2", *parse_param_assignments("gain=oops")));
  EXPECT_FALSE(node.find("g2"));  // a failed create leaves nothing behind
}

}  // namespace
}  // namespace symb::os
