// Embryogenesis (paper VI-A, issue 7 deliverable 4): the task-graph genome's text form and
// operators, and development onto a running node: a valid genome becomes a running graph that
// drives; 1,000 seeded malformed genomes and a set of hand-written bad ones are all rejected
// without touching the node, which keeps running its controller throughout.
#include "symb/evo/embryogenesis/embryogenesis.hpp"

#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "symb/control/control_task_types.hpp"
#include "symb/evo/embryogenesis/task_graph_genome.hpp"
#include "symb/evo/evo_task_types.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/robot/ports.hpp"

namespace symb::evo {
namespace {

using namespace std::chrono_literals;

// A wall on the left of the robot: a ticking stand-in for the IR sensor.
class TickingIr final : public os::Task {
 protected:
  void on_tick() override { send(0, {3000.f, 1500.f, 200.f, 0.f, 0.f, 0.f, 0.f}); }
};

// Counts the wheel commands per sender.
class EmbryoCountingWheels final : public os::Task {
 public:
  std::size_t from(os::TaskId id) const {
    return static_cast<std::size_t>(std::count(sources_.begin(), sources_.end(), id));
  }
  std::size_t total() const { return sources_.size(); }
  float last_left = 0, last_right = 0;

 protected:
  void on_message(const os::Message& m) override {
    if (m.numbers().size() != 2) return;
    sources_.push_back(m.source);
    last_left = m.numbers()[0];
    last_right = m.numbers()[1];
  }

 private:
  std::vector<os::TaskId> sources_;
};

constexpr const char* kBraitenberg = "1.5 2.0 2.5 -2.0 -1.5 0.5 0.5 0.6 -1.5 -2.0 -2.5 2.0 1.5 0.5 0.5 0.6";

// A node with a registry (control and evo types), a ticking `ir`, a counting `wheels` and an mlp
// `controller` between them, running. ir and wheels are made in code and declare the device
// tasks' layouts (sensor vector out, wheel command in), as a robot's do.
struct PlainRobot {
  kernel::VirtualTimeExecutor executor;
  os::TaskTypeRegistry registry;
  std::unique_ptr<os::Node> node;
  EmbryoCountingWheels* wheels = nullptr;
  os::TaskId controller;

  PlainRobot() {
    control::ControlResources resources;
    resources.read_program = [](std::string_view ref) -> kernel::Result<std::string> {
      if (ref == "avoid.mdl2e") return std::string("no such language");
      return kernel::Error{"no file '" + std::string(ref) + "'"};
    };
    EXPECT_TRUE(control::register_control_task_types(registry, resources).ok());
    EXPECT_TRUE(register_evo_task_types(registry, resources).ok());
    node = std::make_unique<os::Node>(executor, os::NodeConfig{.name = "robot", .seed = 7, .types = &registry});
    const os::PortSpec ir_out{0, "ir", robot::layout::kSensorVector};
    const os::PortSpec wheels_in{0, "wheels", robot::layout::kWheelCommand};
    auto ir = node->create("ir", std::make_unique<TickingIr>(),
                           {.priority = 3, .period = 30ms, .ports = os::PortDeclaration{{}, {ir_out}}});
    auto w = std::make_unique<EmbryoCountingWheels>();
    wheels = w.get();
    auto wid =
        node->create("wheels", std::move(w), {.queue_capacity = 32, .ports = os::PortDeclaration{{wheels_in}, {}}});
    const std::vector<os::ParamAssignment> params = {{"weights", kBraitenberg, 1}, {"output_scale", "500", 1}};
    auto c = node->create("mlp", "controller", params);
    EXPECT_TRUE(ir && wid && c);
    controller = *c;
    EXPECT_TRUE(node->hook(*ir, *c).ok());
    EXPECT_TRUE(node->hook(*c, *wid).ok());
  }
  ~PlainRobot() { node->clear(); }
};

// What a rejected development must leave exactly as it was.
using TaskKey = std::tuple<std::uint32_t, std::uint32_t, std::string, std::string, os::TaskState, int>;
using HookKey = std::tuple<std::uint32_t, std::uint32_t, std::string, std::string, std::int32_t, int, bool>;
std::pair<std::vector<TaskKey>, std::vector<HookKey>> snapshot(const os::Node& node) {
  std::vector<TaskKey> tasks;
  for (const os::TaskInfo& t : node.tasks())
    tasks.emplace_back(t.id.index, t.id.generation, t.name, t.type, t.state, t.priority);
  std::vector<HookKey> hooks;
  for (const os::HookInfo& h : node.hooks())
    hooks.emplace_back(h.id.sender_index, h.id.serial, h.sender_name, h.receiver_name, h.options.port,
                       h.options.priority, h.options.enabled);
  return {tasks, hooks};
}

TaskGraphGenome parse(const std::string& text) {
  auto g = parse_task_graph(text);
  EXPECT_TRUE(g.ok()) << (g ? "" : g.error());
  return g ? *g : TaskGraphGenome{};
}

TEST(TaskGraphGenome, ParsesAndRoundTrips) {
  const std::string text =
      "# an avoider and its judge\n"
      "task net mlp weights=\"1 2 3\" output_scale=500\n"
      "  task fit fitness formula=one_plus_one   \n"
      "\n"
      "hook ir -> net\n"
      "hook net->wheels port 0 priority -3\n";
  const TaskGraphGenome g = parse(text);
  ASSERT_EQ(g.tasks.size(), 2u);
  EXPECT_EQ(g.tasks[0].type, "mlp");
  EXPECT_EQ(g.tasks[0].params[0].value, "1 2 3");
  EXPECT_EQ(g.tasks[0].params[1].column, 30u);  // where output_scale starts on its line
  EXPECT_EQ(g.tasks[1].line, 3u);
  ASSERT_EQ(g.hooks.size(), 2u);
  EXPECT_EQ(g.hooks[1].from, "net");
  EXPECT_EQ(g.hooks[1].to, "wheels");
  EXPECT_EQ(g.hooks[1].port, 0);
  EXPECT_EQ(g.hooks[1].priority, -3);
  const TaskGraphGenome again = parse(to_text(g));
  EXPECT_EQ(again, g);
  EXPECT_EQ(to_text(again), to_text(g));
}

TEST(TaskGraphGenome, ErrorsHaveLineAndColumn) {
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"task\n", "1:5: expected task name"},
      {"\n\nbogus a b\n", "3:1: unknown statement 'bogus'"},
      {"task 9x mlp\n", "1:6: '9x' is not a valid task name"},
      {"task a mlp weights=\"1 2\n", "1:20: unterminated quoted value"},
      {"task a mlp x=1 x=2\n", "1:16: parameter 'x' given twice"},
      {"task a mlp x\n", "1:12: expected name=value"},
      {"hook a b\n", "1:8: expected '->'"},
      {"hook a -> b port 70000\n", "1:18: port 70000 is outside 0..65535"},
      {"hook a -> b port x\n", "1:18: expected port"},
      {"hook a -> b priority 1 priority 2\n", "1:24: 'priority' given twice"},
      {"hook a -> b colour red\n", "1:13: unknown hook option 'colour'"},
      {"hook -> b\n", "1:6: expected sender task name"},
      // Ports come from the task types, never from a genome.
      {"task a mlp\n  ports t in=a out=b\n", "2:3: a genome declares no ports: each task's port layouts come from"},
  };
  for (const auto& [text, expected] : bad) {
    auto r = parse_task_graph(text);
    ASSERT_FALSE(r.ok()) << text;
    EXPECT_EQ(r.error().rfind(expected, 0), 0u) << "text: " << text << "error: " << r.error();
  }
}

TEST(TaskGraphGenome, ParameterMutationStaysInsideTheSchema) {
  PlainRobot robot;
  TaskGraphGenome g = parse("task judge arbiter\ntask fit fitness\n");
  kernel::RandomStream random(11);
  for (int i = 0; i < 300; ++i) {
    ASSERT_TRUE(mutate_parameter(g, robot.registry, random));
    ASSERT_TRUE(check_development(g, *robot.node).ok()) << to_text(g) << check_development(g, *robot.node).error();
    ASSERT_EQ(parse(to_text(g)), g);
  }
  EXPECT_FALSE(g.tasks[0].params.empty());
}

TEST(TaskGraphGenome, StructuralOperators) {
  PlainRobot robot;
  TaskGraphGenome g;
  kernel::RandomStream random(5);
  GraphMutationOptions options;
  options.addable_types = {"fitness", "arbiter"};
  EXPECT_FALSE(remove_task(g, random));
  EXPECT_FALSE(remove_hook(g, random));
  ASSERT_TRUE(add_task(g, robot.registry, random, options));
  ASSERT_TRUE(add_task(g, robot.registry, random, options));
  EXPECT_NE(g.tasks[0].name, g.tasks[1].name);
  ASSERT_TRUE(add_hook(g, random, options));
  EXPECT_NE(g.hooks[0].from, g.hooks[0].to);
  const std::string removed = g.tasks[0].name;
  ASSERT_TRUE(remove_task(g, random));
  for (const HookGene& h : g.hooks) {
    EXPECT_TRUE(g.find_task(h.from) || h.from == "ir" || h.from == "wheels");
    EXPECT_TRUE(g.find_task(h.to) || h.to == "ir" || h.to == "wheels");
  }
  int applied[5] = {};
  for (int i = 0; i < 500; ++i) {
    auto m = mutate(g, robot.registry, random, options);
    ASSERT_TRUE(m.has_value());
    ++applied[static_cast<int>(*m)];
    ASSERT_EQ(parse(to_text(g)), g);
  }
  for (int k = 0; k < 5; ++k) EXPECT_GT(applied[k], 20) << to_string(static_cast<GraphMutation>(k));
}

// The genome every malformed one starts from: valid on the plain robot.
constexpr const char* kValid =
    "task net mlp weights=\"1.5 2.0 2.5 -2.0 -1.5 0.5 0.5 0.6 -1.5 -2.0 -2.5 2.0 1.5 0.5 0.5 0.6\" output_scale=500\n"
    "task fit fitness\n"
    "task judge arbiter\n"
    "hook ir -> net\n"
    "hook net -> judge\n"
    "hook ir -> judge\n"
    "hook net -> fit\n";

// One of 13 ways to break a genome, each certain to be rejected whatever mutations came before.
void corrupt(TaskGraphGenome& g, int how, kernel::RandomStream& random) {
  const std::string fresh = "bad" + std::to_string(random.below(1000000));
  const auto task = [&](std::string type, std::vector<os::ParamAssignment> params = {}) {
    g.tasks.push_back({fresh, std::move(type), std::move(params), 0});
  };
  const auto hook = [&](std::string from, std::string to, std::optional<std::int32_t> port = std::nullopt) {
    g.hooks.push_back({std::move(from), std::move(to), port, 0, 0});
  };
  switch (how) {
    case 0: task("no_such_type"); break;
    case 1: task("mlp", {{"inputs", "0", 0}}); break;                  // below its range
    case 2: task("mlp", {{"wieghts", "1", 0}}); break;                 // unknown parameter
    case 3: task("fitness", {{"command_timeout", "soon", 0}}); break;  // not a duration
    case 4: task("mlp", {{"weights", "1 2 3", 0}}); break;             // factory: wrong count
    case 5: task("mdl2e", {{"program", "avoid.mdl2e", 0}}); break;     // factory: no program
    case 6: task("fitness", {{"formula", "speed", 0}}); break;         // factory: no formula
    case 7: g.tasks.push_back({"ir", "fitness", {}, 0}); break;        // the node's name
    case 8:                                                            // twice in the genome
      task("fitness");
      task("arbiter");
      break;
    case 9: hook("ir", "ghost" + fresh); break;  // missing task
    case 10:                                     // a port ir does not send on
      task("fitness");
      hook("ir", fresh, static_cast<std::int32_t>(1 + random.below(100)));
      break;
    case 11: hook("ir", "wheels"); break;      // a sensor vector into the wheels
    case 12: hook("ir", "controller"); break;  // the node has it
    default: break;
  }
}

TEST(Embryogenesis, ThousandMalformedGenomesLeaveTheRunningNodeUntouched) {
  PlainRobot robot;
  robot.executor.run_for(300ms);
  const std::size_t before_commands = robot.wheels->from(robot.controller);
  ASSERT_GT(before_commands, 5u);
  const TaskGraphGenome base = parse(kValid);
  ASSERT_TRUE(check_development(base, *robot.node).ok()) << check_development(base, *robot.node).error();
  GraphMutationOptions options;
  options.addable_types = {"fitness", "arbiter"};
  std::size_t rejected = 0;
  // What each fault's error says; the operators before it may break the genome first (a hook
  // from a fitness task into the wheels), so most, not all, are refused for the fault's reason.
  const char* const kReason[13] = {"unknown task type",
                                   "outside",
                                   "has no parameter 'wieghts'",
                                   "command_timeout",
                                   "weights",
                                   "avoid.mdl2e",
                                   "formula",
                                   "already has a task",
                                   "twice",
                                   "no task 'ghost",
                                   "'ir' sends on port 0 (sensor-vector) only",
                                   "out of 'ir', but 'wheels' reads wheel-command",
                                   "already has this hook"};
  int tried[13] = {}, for_its_reason[13] = {};
  for (std::uint64_t seed = 0; seed < 1000; ++seed) {
    kernel::RandomStream random(seed);
    TaskGraphGenome g = base;
    for (std::uint64_t k = random.below(4); k > 0; --k) mutate(g, robot.registry, random, options);
    corrupt(g, static_cast<int>(seed % 13), random);
    const auto before = snapshot(*robot.node);
    auto made = develop(g, *robot.node);
    ASSERT_FALSE(made.ok()) << "seed " << seed << ":\n" << to_text(g);
    ASSERT_EQ(snapshot(*robot.node), before) << "seed " << seed;
    ++rejected;
    ++tried[seed % 13];
    if (made.error().find(kReason[seed % 13]) != std::string::npos) ++for_its_reason[seed % 13];
    if (seed % 50 == 0) robot.executor.run_for(30ms);  // the node runs on between attempts
  }
  int own = 0;
  for (int k = 0; k < 13; ++k) {
    EXPECT_GT(for_its_reason[k] * 2, tried[k]) << "fault " << k << ": " << kReason[k];
    own += for_its_reason[k];
  }
  std::printf("1000 malformed genomes refused, %d of them for the planted fault's own reason\n", own);
  // Hand-written: texts the parser refuses, and graphs only the node can refuse.
  const std::vector<std::string> hand = {
      "task a mlp\nhook a -> a\n",                     // self-hook
      "task a arbiter\nhook a -> wheels port 1\n",     // the arbiter sends on port 0 only
      "task a arbiter\nhook ir -> a port 1\n",         // ir sends on port 0 only
      "task a arbiter\nhook a -> b\n",                 // no b
      "task a arbiter\nhook ir -> a\nhook ir -> a\n",  // hooked twice
      "task a t\n",                                    // type t is not registered
      "task a arbiter window=0s\n",                    // below the range
      "task a arbiter margin=3\n",                     // above the range
      "task a arbiter margin=\n",                      // empty number
      "task controller arbiter\n",                     // the node's controller
      "task a mlp inputs=7 layers=\"0\"\n",            // factory: bad layers
  };
  for (const std::string& text : hand) {
    auto g = parse_task_graph(text);
    ASSERT_TRUE(g.ok()) << text << g.error();
    const auto before = snapshot(*robot.node);
    auto made = develop(*g, *robot.node);
    ASSERT_FALSE(made.ok()) << text;
    EXPECT_EQ(made.error().rfind("line ", 0), 0u) << made.error();
    ASSERT_EQ(snapshot(*robot.node), before) << text;
    ++rejected;
  }
  EXPECT_EQ(rejected, 1000u + hand.size());
  robot.executor.run_for(300ms);
  EXPECT_GT(robot.wheels->from(robot.controller), before_commands + 5);
  EXPECT_EQ(robot.node->info(robot.controller)->state, os::TaskState::kRunning);
  EXPECT_EQ(robot.node->task_count(), 3u);
}

TEST(Embryogenesis, ValidGenomeDevelopsIntoARunningGraphThatDrives) {
  PlainRobot robot;
  robot.executor.run_for(100ms);
  // A second avoider and an arbiter between both controllers and the wheels.
  const TaskGraphGenome g = parse(
      "task net mlp weights=\"1.5 2.0 2.5 -2.0 -1.5 0.5 0.5 0.6 -1.5 -2.0 -2.5 2.0 1.5 0.5 0.5 0.6\" "
      "output_scale=400\n"
      "task judge arbiter min_samples=5\n"
      "hook ir -> net\n"
      "hook ir -> judge\n"
      "hook net -> judge\n"
      "hook judge -> wheels port 0 priority 2\n");
  auto made = develop(g, *robot.node);
  ASSERT_TRUE(made.ok()) << made.error();
  EXPECT_EQ(made->tasks.size(), 2u);
  EXPECT_EQ(made->hooks.size(), 4u);
  EXPECT_EQ(robot.node->task_count(), 5u);
  const os::TaskId judge = *robot.node->find("judge");
  EXPECT_EQ(robot.node->info(judge)->type, "arbiter");
  EXPECT_EQ(robot.node->info(judge)->state, os::TaskState::kRunning);
  EXPECT_EQ(robot.node->parameters(judge)->integer("min_samples"), 5);
  robot.executor.run_for(1s);
  EXPECT_GT(robot.wheels->from(judge), 20u);
  // The wall is on the left: the developed graph turns right (left wheel faster).
  EXPECT_GT(robot.wheels->last_left, robot.wheels->last_right);
  // Developing the same genome again is refused (names taken), undevelop takes it all down.
  EXPECT_FALSE(develop(g, *robot.node).ok());
  undevelop(*made, *robot.node);
  EXPECT_EQ(robot.node->task_count(), 3u);
  EXPECT_EQ(robot.node->hooks().size(), 2u);
}

}  // namespace
}  // namespace symb::evo
