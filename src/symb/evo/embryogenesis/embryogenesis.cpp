#include "symb/evo/embryogenesis/embryogenesis.hpp"

#include <exception>
#include <memory>
#include <set>
#include <tuple>
#include <utility>

namespace symb::evo {

namespace {

using kernel::Error;

std::string at(std::size_t line) { return line ? "line " + std::to_string(line) + ": " : std::string(); }

// The declared ports of a hook's end, as Node::hook will see them: a genome task has its type's
// (develop() creates it with the type's options), a task the node runs has its own.
struct HookEnd {
  std::string type = "-";
  os::PortDeclaration ports;

  os::PortEnd view(std::string_view task) const { return {task, type, ports.inputs, ports.outputs}; }
};

HookEnd hook_end(std::string_view name, const TaskGraphGenome& genome, const os::Node& node,
                 const os::TaskTypeRegistry& registry) {
  HookEnd end;
  if (const TaskGene* t = genome.find_task(name)) {
    const os::TaskType* type = registry.find(t->type);  // checked before the hooks are
    end.type = type->name;
    end.ports = {type->inputs, type->outputs};
  } else if (auto id = node.find(name)) {
    if (auto info = node.info(*id)) end.type = info->type;
    if (auto ports = node.ports(*id)) end.ports = std::move(*ports);
  }
  return end;
}

}  // namespace

kernel::Status check_development(const TaskGraphGenome& genome, const os::Node& node) {
  const os::TaskTypeRegistry* registry = node.types();
  if (!registry) return Error{"the node has no task-type registry"};
  if (genome.tasks.size() > kMaxGraphTasks || genome.hooks.size() > kMaxGraphHooks)
    return Error{"the genome is larger than the text form allows"};

  std::set<std::string_view> names;
  for (const TaskGene& t : genome.tasks) {
    const std::string where = at(t.line) + "task '" + t.name + "': ";
    if (!os::is_valid_name(t.name)) return Error{where + "not a valid task name"};
    if (!names.insert(t.name).second) return Error{where + "the genome names it twice"};
    if (node.find(t.name)) return Error{where + "the node already has a task of that name"};
    const os::TaskType* type = registry->find(t.type);
    if (!type) return Error{where + registry->unknown_type_error(t.type)};
    auto params = registry->resolve(*type, t.params);
    if (!params) return Error{where + params.error()};
    // The factory has the last word on parameters (a program that does not parse, weights of the
    // wrong count): ask it now, on a task that is thrown away, so creation cannot fail later.
    // A constructor that throws anyway is refused like a factory's error (as Node::create does).
    try {
      auto made = type->make(*params);
      if (!made) return Error{where + made.error()};
      if (!made.value()) return Error{where + "the type's factory made no task"};
    } catch (const std::exception& e) {
      return Error{where + e.what()};
    } catch (...) {
      return Error{where + "the type's factory threw"};
    }
  }

  const std::vector<os::HookInfo> existing = node.hooks();
  std::set<std::tuple<std::string_view, std::string_view, std::int32_t>> hooked;
  for (const HookGene& h : genome.hooks) {
    const std::string where = at(h.line) + "hook " + h.from + " -> " + h.to + ": ";
    for (const std::string* end : {&h.from, &h.to})
      if (!genome.find_task(*end) && !node.find(*end))
        return Error{where + "no task '" + *end + "' in the genome or on the node"};
    if (h.from == h.to) return Error{where + "a task cannot be hooked to itself"};
    if (h.priority < -1000 || h.priority > 1000) return Error{where + "priority outside -1000..1000"};
    const std::int32_t port = h.port.value_or(-1);
    if (h.port && (*h.port < 0 || *h.port > 65535)) return Error{where + "port outside 0..65535"};
    if (!hooked.insert({h.from, h.to, port}).second) return Error{where + "hooked twice in the genome"};
    for (const os::HookInfo& e : existing)
      if (e.sender_name == h.from && e.receiver_name == h.to && e.options.port == port)
        return Error{where + "the node already has this hook"};
    // The rule Node::hook applies, asked before anything is made.
    const HookEnd sender = hook_end(h.from, genome, node, *registry);
    const HookEnd receiver = hook_end(h.to, genome, node, *registry);
    if (auto st = os::check_layouts(sender.view(h.from), receiver.view(h.to), port); !st)
      return Error{where + st.error()};
  }
  return {};
}

kernel::Result<DevelopedGraph> develop(const TaskGraphGenome& genome, os::Node& node) {
  if (auto st = check_development(genome, node); !st) return Error{st.error()};
  DevelopedGraph made;
  const auto fail = [&](const std::string& what) -> kernel::Result<DevelopedGraph> {
    undevelop(made, node);
    return Error{what + " (everything this development made is removed again)"};
  };
  const os::TaskTypeRegistry& registry = *node.types();
  for (const TaskGene& t : genome.tasks) {
    // Not started: nothing runs before the whole graph is hooked.
    os::TaskOptions options = registry.find(t.type)->defaults;
    options.autostart = false;
    auto id = node.create(t.type, t.name, t.params, options);
    if (!id) return fail(at(t.line) + "task '" + t.name + "': " + id.error());
    made.tasks.push_back(*id);
  }
  for (const HookGene& h : genome.hooks) {
    os::HookOptions options;
    options.priority = h.priority;
    options.port = h.port.value_or(-1);
    auto id = node.hook(*node.find(h.from), *node.find(h.to), options);
    if (!id) return fail(at(h.line) + "hook " + h.from + " -> " + h.to + ": " + id.error());
    made.hooks.push_back(*id);
  }
  for (const os::TaskId id : made.tasks)
    if (auto st = node.start(id); !st) return fail("starting a task: " + st.error());
  return made;
}

void undevelop(const DevelopedGraph& graph, os::Node& node) {
  for (const os::HookId id : graph.hooks) (void)node.unhook(id);
  for (const os::TaskId id : graph.tasks) (void)node.remove(id);
}

}  // namespace symb::evo
