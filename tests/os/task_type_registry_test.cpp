#include "symb/os/task_type_registry.hpp"

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"

namespace symb::os {
namespace {

using namespace std::chrono_literals;

// The gain type's parameters: "gain" changes at runtime, "label" does not.
struct GainParams {
  double gain = 1.0;
  std::string label = "g";
};

// Keeps its parameters; counts the live changes it was told of, and refuses a gain of exactly 7.
class GainTask : public Task {
 public:
  explicit GainTask(const GainParams& p) : params(p) { bind_parameters(params); }
  GainParams params;
  int changes = 0;

 protected:
  kernel::Status on_parameter_changed(std::string_view name) override {
    if (name == "gain" && params.gain == 7.0) return kernel::Error{"seven is unlucky"};
    ++changes;
    return {};
  }
};

ParamTable<GainParams> gain_params() {
  ParamTable<GainParams> p;
  p.add("gain", &GainParams::gain).range(0.0, 10.0).doc("factor").live();
  p.add("label", &GainParams::label).range(1.0, 16.0).doc("a label");
  return p;
}

TaskType gain_type() {
  TaskType t = declare_task_type("gain", "multiplies", gain_params(),
                                 [](const GainParams& p) { return std::make_unique<GainTask>(p); });
  t.defaults.period = 10ms;
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

  // Passes the schema but is not live: logged, value unchanged.
  ASSERT_TRUE(node.set_parameter(*id, "label", "other"));
  ex.run_for(1ms);
  EXPECT_EQ(node.parameters(*id)->string("label"), "g");
  EXPECT_NE(node.log().since(0).back().text.find("not changed"), std::string::npos);
  EXPECT_NE(node.log().since(0).back().text.find("keeps its label"), std::string::npos);

  EXPECT_FALSE(node.set_parameter(*id, "gain", "11"));
  EXPECT_FALSE(node.set_parameter(*id, "gian", "1"));
  EXPECT_FALSE(node.create("nosuch", "x", {}));
  EXPECT_FALSE(node.create("gain", "g2", *parse_param_assignments("gain=oops")));
  EXPECT_FALSE(node.find("g2"));  // a failed create leaves nothing behind
}

// Two robots' registries over one shared registry: each finds the shared types and its own, never
// the other robot's; a name cannot be added twice across the two levels; list and hints see both.
TEST(TaskTypeRegistry, RegistriesOverASharedOneKeepTheirOwnTypesApart) {
  auto shared_mut = std::make_shared<TaskTypeRegistry>();
  ASSERT_TRUE(shared_mut->add(gain_type()));
  const std::shared_ptr<const TaskTypeRegistry> shared = shared_mut;
  TaskTypeRegistry a(shared), b(shared);
  TaskType own_a = gain_type();
  own_a.name = "only_a";
  ASSERT_TRUE(a.add(own_a));
  EXPECT_FALSE(a.add(gain_type()));  // already in the shared registry
  EXPECT_TRUE(b.add(own_a));         // b may have its own type of that name: a's is not b's

  EXPECT_EQ(a.find("gain"), shared->find("gain"));  // one copy, found through either handle
  EXPECT_EQ(b.find("gain"), shared->find("gain"));
  ASSERT_NE(a.find("only_a"), nullptr);
  EXPECT_NE(b.find("only_a"), a.find("only_a"));
  EXPECT_EQ(shared->find("only_a"), nullptr);  // nothing leaks into the shared registry
  std::vector<std::string> names;
  for (const TaskType* t : a.list()) names.push_back(t->name);
  EXPECT_EQ(names, (std::vector<std::string>{"gain", "only_a"}));
  EXPECT_NE(TaskTypeRegistry(shared).unknown_type_error("gian").find("did you mean 'gain'"), std::string::npos);

  kernel::VirtualTimeExecutor ex;
  Node na(ex, {"a", 1, 64, &a});
  Node nb(ex, {"b", 2, 64, &b});
  auto ga = na.create("gain", "g", *parse_param_assignments("gain=3"));
  auto gb = nb.create("gain", "g", *parse_param_assignments("gain=5"));
  ASSERT_TRUE(ga && gb);
  EXPECT_EQ(na.parameters(*ga)->real("gain"), 3.0);  // each node's task is its own
  EXPECT_EQ(nb.parameters(*gb)->real("gain"), 5.0);
  EXPECT_TRUE(na.create("only_a", "x", {}));
  TaskTypeRegistry c(shared);  // a third robot that did not add only_a cannot make one
  Node nc(ex, {"c", 3, 64, &c});
  EXPECT_FALSE(nc.create("only_a", "x", {}));
}

TEST(ParamTable, SchemaComesFromTheDeclaration) {
  const TaskType t = gain_type();
  ASSERT_EQ(t.params.size(), 2u);
  EXPECT_EQ(t.params[0].name, "gain");
  EXPECT_EQ(t.params[0].type, ParamType::kReal);
  EXPECT_EQ(std::get<double>(t.params[0].default_value), 1.0);
  EXPECT_EQ(t.params[0].min, 0.0);
  EXPECT_EQ(t.params[0].max, 10.0);
  EXPECT_EQ(t.params[0].doc, "factor");
  EXPECT_EQ(t.params[1].type, ParamType::kString);
  EXPECT_EQ(std::get<std::string>(t.params[1].default_value), "g");
  ASSERT_EQ(t.live.size(), 2u);
  EXPECT_TRUE(t.live[0].apply);
  EXPECT_FALSE(t.live[1].apply);
}

enum class Shape { kRound, kSquare };
struct ShapeParams {
  Shape shape = Shape::kSquare;
  std::uint32_t sides = 4;
  float size = 0.5f;
  kernel::Duration every{2ms};
  bool on = true;
};

TEST(ParamTable, ReadsEveryFieldTypeAndCodecs) {
  ParamTable<ShapeParams> p;
  p.add("shape", &ShapeParams::shape, choice<Shape>("shape", {{"round", Shape::kRound}, {"square", Shape::kSquare}}))
      .range(1, 16);
  p.add("sides", &ShapeParams::sides).range(0, 100);
  p.add("size", &ShapeParams::size).range(0, 1);
  p.add("every", &ShapeParams::every).range(0, 1);
  p.add("on", &ShapeParams::on);
  TaskTypeRegistry reg;
  ASSERT_TRUE(reg.add(
      declare_task_type("shape", "d", std::move(p), [](const ShapeParams&) { return std::make_unique<Task>(); })));
  const TaskType& t = *reg.find("shape");
  EXPECT_EQ(std::get<std::string>(t.params[0].default_value), "square");
  EXPECT_EQ(std::get<std::int64_t>(t.params[1].default_value), 4);
  EXPECT_EQ(std::get<double>(t.params[2].default_value), 0.5);
  EXPECT_EQ(std::get<kernel::Duration>(t.params[3].default_value), kernel::Duration{2ms});
  EXPECT_EQ(std::get<bool>(t.params[4].default_value), true);

  ParamTable<ShapeParams> q;
  q.add("shape", &ShapeParams::shape, choice<Shape>("shape", {{"round", Shape::kRound}, {"square", Shape::kSquare}}));
  q.add("sides", &ShapeParams::sides);
  auto set = reg.resolve(t, *parse_param_assignments("shape=round sides=7"));
  ASSERT_TRUE(set) << set.error();
  auto c = q.read(*set);
  ASSERT_TRUE(c) << c.error();
  EXPECT_EQ(c->shape, Shape::kRound);
  EXPECT_EQ(c->sides, 7u);

  auto bad = reg.resolve(t, *parse_param_assignments("shape=oval"));
  ASSERT_TRUE(bad);
  auto refused = q.read(*bad);
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error(), "shape must be 'round' or 'square', not 'oval'");
}

TEST(ParamTable, LiveChangesGoToTheTasksOwnCopyAndCanBeRefused) {
  TaskTypeRegistry reg;
  ASSERT_TRUE(reg.add(gain_type()));
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"n", 1, 64, &reg});
  auto id = node.create("gain", "g1", *parse_param_assignments("gain=3"));
  ASSERT_TRUE(id) << id.error();
  ASSERT_TRUE(node.set_parameter(*id, "gain", "5"));
  ex.run_for(1ms);
  EXPECT_EQ(node.parameters(*id)->real("gain"), 5.0);
  // The hook refuses 7: the task's copy and the node's record keep 5.
  ASSERT_TRUE(node.set_parameter(*id, "gain", "7"));
  ex.run_for(1ms);
  EXPECT_EQ(node.parameters(*id)->real("gain"), 5.0);
  EXPECT_NE(node.log().since(0).back().text.find("seven is unlucky"), std::string::npos);
}

// A constructor that throws, and one that is asked for an absurd size: creation fails with an
// error naming the type, and the node goes on.
class Throwing : public Task {
 public:
  explicit Throwing(int kind) {
    if (kind == 0) throw std::runtime_error("no luck");
    if (kind == 1) throw 42;
  }
};
struct SizeParams {
  std::int64_t size = 1;
  std::int64_t kind = 0;
};
class Sized : public Task {
 public:
  explicit Sized(std::int64_t n) : data_(static_cast<std::size_t>(n)) {}

 private:
  std::vector<double> data_;
};

void add_failing_types(TaskTypeRegistry& reg) {
  ParamTable<SizeParams> t;
  t.add("kind", &SizeParams::kind).range(0, 1);
  ASSERT_TRUE(reg.add(declare_task_type("throwing", "throws", std::move(t), [](const SizeParams& p) {
    return std::make_unique<Throwing>(static_cast<int>(p.kind));
  })));
  ParamTable<SizeParams> s;
  s.add("size", &SizeParams::size).range(0, 9e18);
  ASSERT_TRUE(reg.add(declare_task_type("sized", "allocates", std::move(s),
                                        [](const SizeParams& p) { return std::make_unique<Sized>(p.size); })));
}

TEST(TaskTypeRegistry, AFactoryThatThrowsIsAnErrorNotACrash) {
  TaskTypeRegistry reg;
  add_failing_types(reg);
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"n", 1, 64, &reg});
  auto a = node.create("throwing", "a", *parse_param_assignments("kind=0"));
  ASSERT_FALSE(a);
  EXPECT_EQ(a.error(), "task type 'throwing' could not make a task: no luck");
  auto b = node.create("throwing", "b", *parse_param_assignments("kind=1"));
  ASSERT_FALSE(b);
  EXPECT_NE(b.error().find("task type 'throwing'"), std::string::npos) << b.error();
  // More than a vector can hold: std::length_error from the constructor.
  auto c = node.create("sized", "c", *parse_param_assignments("size=9000000000000000000"));
  ASSERT_FALSE(c);
  EXPECT_NE(c.error().find("task type 'sized'"), std::string::npos) << c.error();
#ifndef SYMB_SANITIZER
  // More than the system gives: std::bad_alloc. The sanitizers' allocators abort on such a
  // request instead of throwing, so this case runs in the release build only.
  c = node.create("sized", "c", *parse_param_assignments("size=100000000000000000"));
  ASSERT_FALSE(c);
  EXPECT_NE(c.error().find("task type 'sized'"), std::string::npos) << c.error();
#endif
  EXPECT_FALSE(node.find("a") || node.find("b") || node.find("c"));
  EXPECT_TRUE(node.create("sized", "d", *parse_param_assignments("size=10")));
}

// Hooks between declared ports: a wheel command into an IR vector input is refused, naming both.
TEST(TaskTypeRegistry, HooksBetweenIncompatibleLayoutsAreRefused) {
  constexpr PortLayout kIr{"ir", "seven IR readings"};
  constexpr PortLayout kWheels{"wheels", "[left, right]"};
  TaskTypeRegistry reg;
  auto make = [] { return std::make_unique<Task>(); };
  TaskType ctrl = declare_task_type("ctrl", "d", ParamTable<NoParams>{}, [&](const NoParams&) { return make(); });
  ctrl.inputs = {{0, "ir", kIr}};
  ctrl.outputs = {{0, "wheels", kWheels}};
  TaskType any = declare_task_type("sensor", "d", ParamTable<NoParams>{}, [&](const NoParams&) { return make(); });
  any.outputs = {{0, "samples", kAnyLayout}};
  ASSERT_TRUE(reg.add(std::move(ctrl)));
  ASSERT_TRUE(reg.add(std::move(any)));
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"n", 1, 64, &reg});
  auto c1 = *node.create("ctrl", "c1", {});
  auto c2 = *node.create("ctrl", "c2", {});
  auto s = *node.create("sensor", "s", {});
  auto code = *node.create("code", std::make_unique<Task>());
  auto wrong = node.hook(c1, c2);
  ASSERT_FALSE(wrong);
  EXPECT_NE(wrong.error().find("'c1' (ctrl)"), std::string::npos) << wrong.error();
  EXPECT_NE(wrong.error().find("'c2' (ctrl)"), std::string::npos) << wrong.error();
  EXPECT_NE(wrong.error().find("wheels"), std::string::npos) << wrong.error();
  EXPECT_NE(wrong.error().find("ir"), std::string::npos) << wrong.error();
  HookOptions other_port;
  other_port.port = 1;  // c1 declares no output there: the hook would carry nothing
  auto nothing = node.hook(c1, c2, other_port);
  ASSERT_FALSE(nothing);
  EXPECT_NE(nothing.error().find("'c1' sends on port 0 (wheels) only"), std::string::npos) << nothing.error();
  EXPECT_TRUE(node.hook(s, c1));     // "any" matches
  EXPECT_TRUE(node.hook(code, c1));  // made in code without ports: unchecked
  EXPECT_TRUE(node.hook(c1, code));
}

// A task made in code, or a task of a type whose layout says only `any`, may declare its own ports
// when it is created (TaskOptions::ports); every hook it takes part in is then checked like a
// type's. A declaration that contradicts the type's is refused at creation.
TEST(TaskTypeRegistry, ATasksOwnPortDeclarationIsCheckedLikeAType) {
  constexpr PortLayout kIr{"ir", "seven IR readings"};
  constexpr PortLayout kWheels{"wheels", "[left, right]"};
  TaskTypeRegistry reg;
  auto make = [] { return std::make_unique<Task>(); };
  TaskType sink = declare_task_type("sink", "d", ParamTable<NoParams>{}, [&](const NoParams&) { return make(); });
  sink.inputs = {{0, "command", kAnyLayout}};
  TaskType ctrl = declare_task_type("ctrl", "d", ParamTable<NoParams>{}, [&](const NoParams&) { return make(); });
  ctrl.inputs = {{0, "ir", kIr}};
  ASSERT_TRUE(reg.add(std::move(sink)));
  ASSERT_TRUE(reg.add(std::move(ctrl)));
  kernel::VirtualTimeExecutor ex;
  Node node(ex, {"n", 1, 64, &reg});
  TaskOptions ir_options;
  ir_options.ports = PortDeclaration{{}, {{0, "ir", kIr}}};
  auto ir = *node.create("ir", std::make_unique<Task>(), ir_options);
  TaskOptions wheel_options = reg.find("sink")->defaults;
  wheel_options.ports = PortDeclaration{{{0, "wheels", kWheels}}, {}};
  auto wheels = *node.create("sink", "wheels", {}, wheel_options);
  ASSERT_EQ(node.ports(wheels)->inputs.at(0).layout.name, "wheels");
  auto plain = *node.create("sink", "plain", {});  // the type's own: any
  auto c = *node.create("ctrl", "c", {});
  auto wrong = node.hook(ir, wheels);
  ASSERT_FALSE(wrong);
  for (const char* part : {"'ir' (-)", "'wheels' (sink)", "carries ir (seven IR readings)", "reads wheels"})
    EXPECT_NE(wrong.error().find(part), std::string::npos) << part << " in " << wrong.error();
  EXPECT_TRUE(node.hook(ir, plain));
  EXPECT_TRUE(node.hook(ir, c));
  EXPECT_TRUE(node.hooks().size() == 2);
  // ctrl reads ir on port 0: a task of it cannot claim to read wheels there.
  TaskOptions contradicting;
  contradicting.ports = PortDeclaration{{{0, "wheels", kWheels}}, {}};
  auto bad = node.create("ctrl", "c2", {}, contradicting);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().find("input port 0 declared wheels, but type 'ctrl' declares ir"), std::string::npos)
      << bad.error();
  EXPECT_FALSE(node.find("c2"));
}

}  // namespace
}  // namespace symb::os
