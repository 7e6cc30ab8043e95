#include "symb/control/cpg/cpg_task_types.hpp"

#include <memory>
#include <numbers>

#include "symb/control/cpg/oscillator_task.hpp"
#include "symb/robot/ports.hpp"

namespace symb::control {

using namespace std::chrono_literals;

kernel::Status register_cpg_task_types(os::TaskTypeRegistry& registry, const ControlResources& /*resources*/) {
  using cpg::OscillatorOptions;
  constexpr double kPi = std::numbers::pi;
  os::ParamTable<OscillatorOptions> p;
  p.add("id", &OscillatorOptions::id).range(0, 1 << 20).doc("this oscillator's place in its chain").live();
  p.add("frequency", &OscillatorOptions::frequency).range(0.0, 50.0).doc("Hz").live();
  p.add("amplitude", &OscillatorOptions::amplitude).range(0.0, kPi).doc("of the joint target, rad").live();
  p.add("offset", &OscillatorOptions::offset).range(-kPi, kPi).doc("the joint target's centre, rad").live();
  p.add("coupling", &OscillatorOptions::coupling)
      .range(0.0, 100.0)
      .doc("how hard a neighbour's phase pulls, rad/s")
      .live();
  p.add("lag", &OscillatorOptions::lag)
      .range(-2 * kPi, 2 * kPi)
      .doc("rad that each oscillator trails the one before it (id - 1)")
      .live();
  p.add("neighbour_timeout", &OscillatorOptions::neighbour_timeout)
      .range(0.001, 3600.0)
      .doc("a neighbour not heard from for this long stops pulling")
      .live();
  p.add("initial_phase", &OscillatorOptions::initial_phase).range(-2 * kPi, 2 * kPi).doc("rad");
  p.add("random_phase", &OscillatorOptions::random_phase)
      .doc("start at a phase drawn from the task's random stream instead of initial_phase");
  auto t = os::declare_task_type(
      "oscillator",
      "CPG phase oscillator: neighbours' [id, phase] in on port 1; the joint target [angle] out on port 0 and "
      "[id, phase] on port 1 at every tick",
      std::move(p), [](const OscillatorOptions& o) -> kernel::Result<std::unique_ptr<cpg::OscillatorTask>> {
        return std::make_unique<cpg::OscillatorTask>(o);
      });
  t.defaults = os::TaskOptions{.priority = 2, .period = 20ms, .queue_capacity = 8};
  t.inputs = {{cpg::kPhasePort, "phases", robot::layout::kOscillatorPhase}};
  t.outputs = {{cpg::kJointTargetPort, "joint", robot::layout::kJointTarget},
               {cpg::kPhasePort, "phase", robot::layout::kOscillatorPhase}};
  return registry.add(std::move(t));
}

}  // namespace symb::control
