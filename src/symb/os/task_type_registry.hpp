// TaskTypeRegistry: task types by name, each with a parameter schema and a factory, so that the
// shell, scenario files and genomes can all create any task at runtime by naming it (ARGoS-style
// registration). A registry is an ordinary object handed to the nodes that use it; there is no
// process-wide one.
//
// Shared types: a registry may be made over a read-only registry of types that capture nothing of
// one robot (the control and evo layers' types, whose factories need only the session's program
// reader), shared by every identical robot of a swarm; it adds its own (the robot's device tasks,
// whose factories hold that robot's devices). Each node still looks types up through its own
// registry, so what one robot adds is seen by that robot only. The type tables are the bulk of a
// robot's memory otherwise (about 200 KB: schemas, docs and factories of some fifty types).
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "symb/kernel/result.hpp"
#include "symb/os/param.hpp"
#include "symb/os/param_table.hpp"
#include "symb/os/port_layout.hpp"
#include "symb/os/task.hpp"

namespace symb::os {

// Makes a task from resolved parameters; an error says why not (it becomes the creation error,
// naming the type). Never throws by contract; Node::create still catches what a constructor throws.
using TaskFactory = std::function<kernel::Result<std::unique_ptr<Task>>(const ParamSet&)>;

// A registered type: what the registry and its users see. Made by declare_task_type() from a
// ParamTable, so the schema, the factory's config and the live changes come from one declaration.
struct TaskType {
  std::string name;
  std::string doc;
  std::vector<ParamSpec> params;
  // How a running task takes a new value, one per params entry (empty: no parameter is live).
  std::vector<LiveParam> live;
  TaskOptions defaults;  // priority, period and queue size unless the creator says otherwise
  // Declared ports (empty: unchecked). A hook whose sender's output and receiver's input share a
  // port number with incompatible layouts is refused (Node::hook).
  std::vector<PortSpec> inputs;
  std::vector<PortSpec> outputs;
  TaskFactory make;

  const ParamSpec* param(std::string_view param_name) const;
};

// A task type declared from its parameter table and a factory that receives the filled config:
//
//   os::ParamTable<NoiseOptions> p;
//   p.add("gain", &NoiseOptions::gain).range(0.0, 1000.0).doc("the schema's gain").live();
//   auto t = os::declare_task_type("noise", "motor schema: ...", std::move(p),
//       [](const NoiseOptions& o) -> kernel::Result<std::unique_ptr<os::Task>> {
//         return std::make_unique<NoiseSchema>(o);
//       });
//
// `make` takes a const Config& and returns a Result of a unique_ptr to a Task (or to a class
// derived from it), or such a unique_ptr; its errors are values, not exceptions.
template <class Config, class Make>
TaskType declare_task_type(std::string name, std::string doc, ParamTable<Config> params, Make make) {
  TaskType t;
  t.name = std::move(name);
  t.doc = std::move(doc);
  t.params = params.specs();
  t.live = params.live_params();
  auto table = std::make_shared<const ParamTable<Config>>(std::move(params));
  t.make = [table, make = std::move(make)](const ParamSet& values) -> kernel::Result<std::unique_ptr<Task>> {
    auto config = table->read(values);
    if (!config) return kernel::Error{config.error()};
    auto made = make(config.value());
    if constexpr (requires { made.error(); }) {
      if (!made) return kernel::Error{made.error()};
      return std::unique_ptr<Task>(std::move(made).value());
    } else {
      return std::unique_ptr<Task>(std::move(made));
    }
  };
  return t;
}

// The config of a type without parameters.
struct NoParams {};

class TaskTypeRegistry {
 public:
  TaskTypeRegistry() = default;
  // Over `shared` (may be null): its types are found as this registry's own; it must not change
  // while this registry is in use (it is const for everyone who shares it).
  explicit TaskTypeRegistry(std::shared_ptr<const TaskTypeRegistry> shared) : shared_(std::move(shared)) {}

  // Fails on a duplicate (in this registry or the shared one) or invalid name, a missing factory,
  // or a schema whose defaults do not satisfy their own type and range.
  kernel::Status add(TaskType type);
  // This registry's own types first, then the shared ones.
  const TaskType* find(std::string_view name) const;
  // All types, own and shared, sorted by name.
  std::vector<const TaskType*> list() const;
  // Defaults overridden by `given`; errors name the parameter (with a hint for a misspelt one)
  // and the column the assignment started at.
  kernel::Result<ParamSet> resolve(const TaskType& type, std::span<const ParamAssignment> given) const;
  // An error for an unknown type name, with a "did you mean" hint.
  std::string unknown_type_error(std::string_view name) const;
  // The shared registry, or null.
  const std::shared_ptr<const TaskTypeRegistry>& shared() const { return shared_; }

 private:
  std::shared_ptr<const TaskTypeRegistry> shared_;
  std::map<std::string, TaskType, std::less<>> types_;
};

}  // namespace symb::os
