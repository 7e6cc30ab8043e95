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

bool compatible(std::string_view sent, std::string_view taken) {
  return sent == "any" || taken == "any" || sent == taken;
}

// The signature of a task the genome or the node has, by name then type; null when unknown.
struct SignatureLookup {
  const PortSignatures& table;
  const TaskGraphGenome& genome;
  const os::Node& node;

  const PortSignature* of_type(std::string_view type, PortSignature& scratch) const {
    if (auto it = table.by_type.find(type); it != table.by_type.end()) return &it->second;
    for (const PortsGene& p : genome.ports)
      if (p.type == type) {
        scratch.input = p.input;
        scratch.outputs = p.outputs;
        return &scratch;
      }
    return nullptr;
  }
  const PortSignature* of_task(std::string_view name, PortSignature& scratch) const {
    if (const TaskGene* t = genome.find_task(name)) return of_type(t->type, scratch);
    if (auto it = table.by_task.find(name); it != table.by_task.end()) return &it->second;
    if (auto id = node.find(name))
      if (auto info = node.info(*id)) return of_type(info->type, scratch);
    return nullptr;
  }
};

}  // namespace

PortSignatures robot_port_signatures() {
  PortSignatures s;
  s.by_task["ir"] = {"none", {"ir"}};
  s.by_task["wheels"] = {"wheels", {"none"}};
  s.by_type["mdl2e"] = {"ir", {"wheels"}};
  s.by_type["arbiter"] = {"any", {"wheels"}};
  s.by_type["fitness"] = {"any", {"fitness"}};
  return s;
}

kernel::Status check_development(const TaskGraphGenome& genome, const os::Node& node,
                                 const PortSignatures& signatures) {
  const os::TaskTypeRegistry* registry = node.types();
  if (!registry) return Error{"the node has no task-type registry"};
  if (genome.tasks.size() > kMaxGraphTasks || genome.hooks.size() > kMaxGraphHooks)
    return Error{"the genome is larger than the text form allows"};

  std::set<std::string_view> types_declared;
  for (const PortsGene& p : genome.ports) {
    if (!os::is_valid_name(p.type)) return Error{at(p.line) + "'" + p.type + "' is not a valid type name"};
    if (!types_declared.insert(p.type).second) return Error{at(p.line) + "ports of '" + p.type + "' given twice"};
    if (p.outputs.empty() || p.outputs.size() > kMaxPortsPerType || !os::is_valid_name(p.input))
      return Error{at(p.line) + "ports of '" + p.type + "': one input kind and 1 to " +
                   std::to_string(kMaxPortsPerType) + " output kinds"};
    for (const std::string& k : p.outputs)
      if (!os::is_valid_name(k)) return Error{at(p.line) + "'" + k + "' is not a valid port kind"};
    if (auto it = signatures.by_type.find(p.type); it != signatures.by_type.end())
      if (it->second.input != p.input || it->second.outputs != p.outputs)
        return Error{at(p.line) + "ports of '" + p.type + "' differ from the type's known signature"};
  }

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

  const SignatureLookup lookup{signatures, genome, node};
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
    PortSignature s1, s2;
    const PortSignature* sender = lookup.of_task(h.from, s1);
    const PortSignature* receiver = lookup.of_task(h.to, s2);
    if (sender && h.port && static_cast<std::size_t>(*h.port) >= sender->outputs.size())
      return Error{where + "port " + std::to_string(*h.port) + " is not an output of '" + h.from + "' (it has " +
                   std::to_string(sender->outputs.size()) + ")"};
    if (sender && receiver) {
      for (std::size_t p = 0; p < sender->outputs.size(); ++p) {
        if (h.port && static_cast<std::size_t>(*h.port) != p) continue;
        if (!compatible(sender->outputs[p], receiver->input))
          return Error{where + "'" + h.from + "' sends " + sender->outputs[p] + " on port " + std::to_string(p) +
                       ", '" + h.to + "' takes " + receiver->input};
      }
    }
  }
  return {};
}

kernel::Result<DevelopedGraph> develop(const TaskGraphGenome& genome, os::Node& node,
                                       const PortSignatures& signatures) {
  if (auto st = check_development(genome, node, signatures); !st) return Error{st.error()};
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
