// Embryogenesis (paper section VI-A): a task-graph genome (task_graph_genome.hpp) developed into a
// running graph of tasks and hooks on a node, at runtime. Development is all or nothing: every
// statement is checked first against the node's registry and current tasks and hooks (unknown
// types, parameters through the type's schema and factory, names taken, hooks to missing tasks,
// self-hooks, duplicate hooks, ports out of range, and port layouts that do not match by the rule
// Node::hook applies, os::check_layouts: a genome task has its type's declared ports, a task the
// node runs its own, such as the device tasks ir and wheels), and only then are the tasks created
// (not started), hooked and started. A rejected genome leaves the node exactly as it was; should
// the node itself refuse a step after the checks (it should not), what was made is taken down
// again before the error is returned.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "symb/evo/embryogenesis/task_graph_genome.hpp"
#include "symb/kernel/result.hpp"
#include "symb/os/ids.hpp"
#include "symb/os/node.hpp"

namespace symb::evo {

// What a development made, to take it down again (undevelop) or to find its tasks.
struct DevelopedGraph {
  std::vector<os::TaskId> tasks;
  std::vector<os::HookId> hooks;
};

// Checks `genome` against `node` without changing anything. Errors name the genome's line.
kernel::Status check_development(const TaskGraphGenome& genome, const os::Node& node);
// check_development(), then creates, hooks and starts everything.
kernel::Result<DevelopedGraph> develop(const TaskGraphGenome& genome, os::Node& node);
// Removes a developed graph's hooks and tasks (those still there).
void undevelop(const DevelopedGraph& graph, os::Node& node);

}  // namespace symb::evo
