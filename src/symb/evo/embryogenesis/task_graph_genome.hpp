// TaskGraphGenome: a genome that encodes a task graph (paper section VI-A, embryogenesis): which
// task types run, with which parameters, and how they are hooked. It is developed into a running
// graph on a node by develop() (embryogenesis.hpp), which checks it completely first. The text
// form stays close to the shell's and the scenario files' syntax, one statement a line:
//
//   # a comment (whole lines only)
//   task controller mdl2e program=mdl2e/obstacle_avoidance.mdl2e
//   task net mlp inputs=7 layers="2" weights="1 2 3 ..."
//   hook ir -> controller
//   hook controller -> wheels port 0 priority 2
//
// `task NAME TYPE key=value ...` names a task of a registered type (the values go through the
// type's ParamSpec schema at development); `hook FROM -> TO [port N] [priority P]` hooks two
// tasks, each either the genome's own or one the node already runs (`ir`, `wheels`). A genome
// declares no ports: each task's port layouts come from its task type (TaskType::inputs,
// outputs), a device task's from the node, and development checks every hook against them (see
// embryogenesis.hpp). The operators below
// change a parameter within its schema range, add or remove a task of a registered type, and add
// or remove a hook; they never make a text the parser rejects, but may make a graph develop()
// rejects (that is the selection's business).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/result.hpp"
#include "symb/os/param.hpp"
#include "symb/os/task_type_registry.hpp"

namespace symb::evo {

struct TaskGene {
  std::string name;
  std::string type;
  std::vector<os::ParamAssignment> params;  // columns are the text's (0 when made by an operator)
  std::size_t line = 0;                     // 0 when made by an operator

  bool operator==(const TaskGene& o) const;
};

struct HookGene {
  std::string from;
  std::string to;
  std::optional<std::int32_t> port;  // the sender's output port; all ports when absent
  int priority = 0;
  std::size_t line = 0;

  bool operator==(const HookGene& o) const {
    return from == o.from && to == o.to && port == o.port && priority == o.priority;
  }
};

struct TaskGraphGenome {
  std::vector<TaskGene> tasks;
  std::vector<HookGene> hooks;

  bool operator==(const TaskGraphGenome& o) const { return tasks == o.tasks && hooks == o.hooks; }
  const TaskGene* find_task(std::string_view name) const;
};

// Limits of the text form (a genome is small; these keep a hostile text from costing much).
inline constexpr std::size_t kMaxGraphText = 1 << 20;
inline constexpr std::size_t kMaxGraphTasks = 256;
inline constexpr std::size_t kMaxGraphHooks = 1024;

// Parses the text form; errors are "LINE:COLUMN: message". Checks only what the text alone
// decides (syntax, names, numbers, limits); develop() checks the rest against a node.
kernel::Result<TaskGraphGenome> parse_task_graph(std::string_view text);
// The canonical text; parse_task_graph() reads it back to an equal genome (lines aside).
std::string to_text(const TaskGraphGenome& genome);

enum class GraphMutation : std::uint8_t { kParameter, kAddTask, kRemoveTask, kAddHook, kRemoveHook };
const char* to_string(GraphMutation m);

struct GraphMutationOptions {
  // Types kAddTask may add; empty: every registered type.
  std::vector<std::string> addable_types;
  // Tasks outside the genome that hooks may name (the node's device tasks).
  std::vector<std::string> external_tasks = {"ir", "wheels"};
  // A real or duration parameter moves by a Gaussian step of this share of its range.
  double step_share = 0.1;
};

// Each returns false (and leaves the genome alone) when it has nothing to work on.
// A numeric or boolean parameter of a task of a registered type: a new value within its range
// (reflected at the bounds), written as the schema's canonical text.
bool mutate_parameter(TaskGraphGenome& g, const os::TaskTypeRegistry& registry, kernel::RandomStream& random,
                      const GraphMutationOptions& options = {});
// A task of a registered type with its defaults, under a fresh name.
bool add_task(TaskGraphGenome& g, const os::TaskTypeRegistry& registry, kernel::RandomStream& random,
              const GraphMutationOptions& options = {});
// A task and every hook that names it.
bool remove_task(TaskGraphGenome& g, kernel::RandomStream& random);
// A hook between two distinct tasks (the genome's or external ones) not hooked yet.
bool add_hook(TaskGraphGenome& g, kernel::RandomStream& random, const GraphMutationOptions& options = {});
bool remove_hook(TaskGraphGenome& g, kernel::RandomStream& random);
// One of the five, drawn uniformly among those that can apply; nullopt when none can.
std::optional<GraphMutation> mutate(TaskGraphGenome& g, const os::TaskTypeRegistry& registry,
                                    kernel::RandomStream& random, const GraphMutationOptions& options = {});

}  // namespace symb::evo
