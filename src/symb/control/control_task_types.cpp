#include "symb/control/control_task_types.hpp"

#include <memory>
#include <stdexcept>

#include "symb/control/ahhs_task_types.hpp"
#include "symb/control/behaviour_task_types.hpp"
#include "symb/control/mdl2e/compiler.hpp"
#include "symb/control/mdl2e_task.hpp"
#include "symb/control/network_task_types.hpp"
#include "symb/control/snn_task_types.hpp"

namespace symb::control {

namespace {

using namespace std::chrono_literals;
using os::ParamSpec;
using os::ParamType;

// Reference texts are echoed in errors; a reference longer than this is cut there.
constexpr std::size_t kShownReference = 120;

std::string shown(const std::string& reference) {
  if (reference.size() <= kShownReference) return reference;
  return reference.substr(0, kShownReference) + "...";
}

}  // namespace

kernel::Status register_control_task_types(os::TaskTypeRegistry& registry, ControlResources resources) {
  auto shared = std::make_shared<const ControlResources>(std::move(resources));
  const Mdl2eTaskOptions d;

  os::TaskType mdl2e_type;
  mdl2e_type.name = "mdl2e";
  mdl2e_type.doc =
      "runs an MDL2e program: sensor vectors in on port 0, external interrupt bits on port 1, [left, right] "
      "wheel speeds out on port 0 at every step";
  mdl2e_type.params = {
      {"program", ParamType::kString, std::string(), 0.0, 1024.0, "the program to run (a reference the node resolves)"},
      {"speed_limit", ParamType::kReal, d.speed_limit, 0.001, 1e6, "wheel speeds are clamped to +-this"},
      {"warn_interval", ParamType::kDuration, d.warn_interval, 0.0, 3600.0,
       "at most one warning of a kind per interval (counts say how many it stands for)"},
  };
  mdl2e_type.defaults.priority = 2;
  mdl2e_type.defaults.period = 30ms;
  mdl2e_type.defaults.queue_capacity = 4;
  // TaskType::make's only way to explain a failure is an exception; the node turns it into the
  // creation error, naming the type.
  mdl2e_type.make = [shared](const os::ParamSet& p) -> std::unique_ptr<os::Task> {
    const std::string& reference = p.string("program");
    if (reference.empty()) throw std::invalid_argument("name the program to run: program=REFERENCE");
    if (!shared->read_program) throw std::invalid_argument("this node cannot read programs (no read_program)");
    auto text = shared->read_program(reference);
    if (!text) throw std::invalid_argument("program '" + shown(reference) + "': " + text.error());
    auto compiled = mdl2e::compile_source(*text);
    if (!compiled) throw std::invalid_argument("program '" + shown(reference) + "': " + compiled.error());
    Mdl2eTaskOptions o;
    o.speed_limit = p.real("speed_limit");
    o.warn_interval = p.duration("warn_interval");
    auto task = Mdl2eTask::create(std::make_shared<const mdl2e::Program>(std::move(compiled).value()), o);
    if (!task) throw std::invalid_argument("program '" + shown(reference) + "': " + task.error());
    return std::move(task).value();
  };

  if (auto st = registry.add(std::move(mdl2e_type)); !st) return st;
  if (auto st = register_ahhs_task_types(registry, *shared); !st) return st;
  if (auto st = register_network_task_types(registry, *shared); !st) return st;
  if (auto st = register_behaviour_task_types(registry, *shared); !st) return st;
  return register_snn_task_types(registry, *shared);
}

}  // namespace symb::control
