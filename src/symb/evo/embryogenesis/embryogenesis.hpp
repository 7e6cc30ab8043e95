// Embryogenesis (paper section VI-A): a task-graph genome (task_graph_genome.hpp) developed into a
// running graph of tasks and hooks on a node, at runtime. Development is all or nothing: every
// statement is checked first against the node's registry and current tasks and hooks (unknown
// types, parameters through the type's schema and factory, names taken, hooks to missing tasks,
// self-hooks, duplicate hooks, ports out of range and port kinds that do not match), and only then
// are the tasks created (not started), hooked and started. A rejected genome leaves the node
// exactly as it was; should the node itself refuse a step after the checks (it should not), what
// was made is taken down again before the error is returned.
//
// Port kinds: the registry knows no ports, so the developer carries a small table of signatures,
// by task name (device tasks made in code, such as ir and wheels) and by type: the kind each type
// takes in and the kind it sends on each output port. A hook's port must be one of the sender's
// outputs, and the sender's kind must be the receiver's (or either be `any`). Tasks whose
// signature nobody knows take and send `any` on any port. A genome may add signatures for types
// the table lacks (its `ports` lines), never change the table's.
#pragma once

#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "symb/evo/embryogenesis/task_graph_genome.hpp"
#include "symb/kernel/result.hpp"
#include "symb/os/ids.hpp"
#include "symb/os/node.hpp"

namespace symb::evo {

struct PortSignature {
  std::string input = "any";
  std::vector<std::string> outputs = {"any"};
};

struct PortSignatures {
  std::map<std::string, PortSignature, std::less<>> by_task;  // wins over by_type
  std::map<std::string, PortSignature, std::less<>> by_type;
};

// The robots' ones: ir sends ir readings, wheels takes wheel commands; mdl2e takes ir and sends
// wheels; arbiter takes any (readings and commands) and sends wheels; fitness takes any and sends
// fitness; mlp and the other networks take and send any (their meaning depends on parameters).
PortSignatures robot_port_signatures();

// What a development made, to take it down again (undevelop) or to find its tasks.
struct DevelopedGraph {
  std::vector<os::TaskId> tasks;
  std::vector<os::HookId> hooks;
};

// Checks `genome` against `node` without changing anything. Errors name the genome's line.
kernel::Status check_development(const TaskGraphGenome& genome, const os::Node& node,
                                 const PortSignatures& signatures = robot_port_signatures());
// check_development(), then creates, hooks and starts everything.
kernel::Result<DevelopedGraph> develop(const TaskGraphGenome& genome, os::Node& node,
                                       const PortSignatures& signatures = robot_port_signatures());
// Removes a developed graph's hooks and tasks (those still there).
void undevelop(const DevelopedGraph& graph, os::Node& node);

}  // namespace symb::evo
