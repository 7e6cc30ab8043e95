// TaskTypeRegistry: task types by name, each with a parameter schema and a factory, so that the
// shell, scenario files and genomes can all create any task at runtime by naming it (ARGoS-style
// registration). A registry is an ordinary object handed to the nodes that use it; there is no
// process-wide one.
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
#include "symb/os/task.hpp"

namespace symb::os {

struct TaskType {
  std::string name;
  std::string doc;
  std::vector<ParamSpec> params;
  TaskOptions defaults;  // priority, period and queue size unless the creator says otherwise
  std::function<std::unique_ptr<Task>(const ParamSet&)> make;

  const ParamSpec* param(std::string_view param_name) const;
};

class TaskTypeRegistry {
 public:
  // Fails on a duplicate or invalid name, a missing factory, or a schema whose defaults do not
  // satisfy their own type and range.
  kernel::Status add(TaskType type);
  const TaskType* find(std::string_view name) const;
  // All types, sorted by name.
  std::vector<const TaskType*> list() const;
  // Defaults overridden by `given`; errors name the parameter (with a hint for a misspelt one)
  // and the column the assignment started at.
  kernel::Result<ParamSet> resolve(const TaskType& type, std::span<const ParamAssignment> given) const;
  // An error for an unknown type name, with a "did you mean" hint.
  std::string unknown_type_error(std::string_view name) const;

 private:
  std::map<std::string, TaskType, std::less<>> types_;
};

}  // namespace symb::os
