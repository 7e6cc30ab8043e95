#include "symb/control/mdl2e/mdl2e_task_types.hpp"

#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>

#include "symb/control/mdl2e/compiler.hpp"
#include "symb/control/mdl2e/mdl2e_task.hpp"
#include "symb/robot/ports.hpp"

namespace symb::control {

using namespace std::chrono_literals;

namespace {

// One compiled program per text among the tasks this registry makes: a swarm's robots running
// the same file share its bytecode (read-only) instead of each holding a copy, so a step reads
// code that is already in the cache. Compiling is a pure function of the text, so sharing changes
// no run. Entries of programs no task uses any more are swept as new ones come.
class CompiledPrograms {
 public:
  kernel::Result<std::shared_ptr<const mdl2e::Program>> get(const std::string& text) {
    std::lock_guard lock(mu_);
    if (auto it = by_text_.find(text); it != by_text_.end())
      if (auto shared = it->second.lock()) return shared;
    auto compiled = mdl2e::compile_source(text);
    if (!compiled) return kernel::Error{compiled.error()};
    auto program = std::make_shared<const mdl2e::Program>(std::move(compiled).value());
    if (by_text_.size() >= kSweepAt) std::erase_if(by_text_, [](const auto& e) { return e.second.expired(); });
    by_text_[text] = program;
    return program;
  }

 private:
  static constexpr std::size_t kSweepAt = 64;
  std::mutex mu_;
  std::unordered_map<std::string, std::weak_ptr<const mdl2e::Program>> by_text_;
};

}  // namespace

kernel::Status register_mdl2e_task_types(os::TaskTypeRegistry& registry, const ControlResources& resources) {
  os::ParamTable<Mdl2eParams> p;
  p.add("program", &Mdl2eParams::program).range(0, 1024).doc("the program to run (a reference the node resolves)");
  p.add("speed_limit", &Mdl2eParams::speed_limit).range(0.001, 1e6).doc("wheel speeds are clamped to +-this").live();
  p.add("warn_interval", &Mdl2eParams::warn_interval)
      .range(0.0, 3600.0)
      .doc("at most one warning of a kind per interval (counts say how many it stands for)")
      .live();
  auto mdl2e_type = os::declare_task_type(
      "mdl2e",
      "runs an MDL2e program: sensor vectors in on port 0, external interrupt bits on port 1, [left, right] "
      "wheel speeds out on port 0 at every step",
      std::move(p),
      [read_program = resources.read_program, devices = resources.device,
       programs =
           std::make_shared<CompiledPrograms>()](const Mdl2eParams& o) -> kernel::Result<std::unique_ptr<Mdl2eTask>> {
        if (o.program.empty()) return kernel::Error{"name the program to run: program=REFERENCE"};
        if (!read_program) return kernel::Error{"this node cannot read programs (no read_program)"};
        auto text = read_program(o.program);
        if (!text) return kernel::Error{"program '" + shown_reference(o.program) + "': " + text.error()};
        auto compiled = programs->get(*text);
        if (!compiled) return kernel::Error{"program '" + shown_reference(o.program) + "': " + compiled.error()};
        auto task = Mdl2eTask::create(std::move(compiled).value(), o, devices);
        if (!task) return kernel::Error{"program '" + shown_reference(o.program) + "': " + task.error()};
        return task;
      });
  // Below the sensor type's 1: at an instant where a reading and a tick meet, the reading is
  // queued first and the tick leaves the step to it, so the controller steps once a period on the
  // newest data instead of twice (once on the previous vector, a command the wheels never keep).
  mdl2e_type.defaults.priority = 0;
  mdl2e_type.defaults.period = 30ms;
  mdl2e_type.defaults.queue_capacity = 4;
  mdl2e_type.inputs = {{kSensorPort, "sensors", robot::layout::kSensorVector},
                       {kExternalPort, "external", robot::layout::kExternalBit}};
  mdl2e_type.outputs = {{kWheelPort, "wheels", robot::layout::kWheelCommand}};

  return registry.add(std::move(mdl2e_type));
}

}  // namespace symb::control
