// check_scenario: the half of validation that needs the runner's task types. Kept apart from the
// parser so a scenario can be read (and shown, or edited) without knowing what will run it.
#include <cctype>
#include <span>

#include "symb/sim/scenario.hpp"

namespace symb::sim {
namespace {

// TaskTypeRegistry::resolve prefixes "column N: " (it was made for shell lines); here the
// location comes from the file instead.
std::string without_column(const std::string& msg) {
  constexpr std::string_view kPrefix = "column ";
  if (msg.compare(0, kPrefix.size(), kPrefix) != 0) return msg;
  std::size_t i = kPrefix.size();
  while (i < msg.size() && std::isdigit(static_cast<unsigned char>(msg[i]))) ++i;
  if (i + 1 < msg.size() && msg[i] == ':' && msg[i + 1] == ' ') return msg.substr(i + 2);
  return msg;
}

}  // namespace

kernel::Status check_scenario(const Scenario& scenario, const os::TaskTypeRegistry& types) {
  for (const auto& robot : scenario.robots) {
    for (const auto& task : robot.tasks) {
      const os::TaskType* type = types.find(task.type);
      const SourceLocation& type_at = task.type_where.line > 0 ? task.type_where : task.where;
      if (type == nullptr) return kernel::Error{type_at.str() + ": " + types.unknown_type_error(task.type)};
      // One parameter at a time, so an error points at the parameter that caused it.
      for (std::size_t i = 0; i < task.params.size(); ++i) {
        auto one = types.resolve(*type, std::span(&task.params[i], 1));
        if (!one) {
          const SourceLocation& at = i < task.param_where.size() ? task.param_where[i] : task.where;
          return kernel::Error{at.str() + ": task '" + task.name + "': " + without_column(one.error())};
        }
      }
      if (auto all = types.resolve(*type, task.params); !all)
        return kernel::Error{task.where.str() + ": task '" + task.name + "': " + without_column(all.error())};
    }
  }
  return {};
}

}  // namespace symb::sim
