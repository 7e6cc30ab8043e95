#include "symb/evo/evo_task_types.hpp"

#include <memory>
#include <string>

#include "symb/control/network/network.hpp"
#include "symb/evo/arbiter/arbiter_task.hpp"
#include "symb/evo/controller_swap.hpp"
#include "symb/evo/fitness/fitness_task.hpp"
#include "symb/evo/medea/medea_task.hpp"
#include "symb/evo/mu_plus_one/mu_plus_one_task.hpp"
#include "symb/evo/one_plus_one/one_plus_one_task.hpp"

namespace symb::evo {

namespace {

using namespace std::chrono_literals;

using kernel::Error;
using kernel::Result;

os::TaskType fitness_type() {
  using P = FitnessTaskOptions;
  os::ParamCodec<FitnessFormula> formula;
  formula.type = os::ParamType::kString;
  formula.parse = [](const os::ParamValue& v) -> Result<FitnessFormula> {
    const auto& text = std::get<std::string>(v);
    const auto f = parse_fitness_formula(text);
    if (!f) return Error{"formula: '" + text + "' is none of floreano_mondada, one_plus_one, liolib"};
    return *f;
  };
  formula.format = [](FitnessFormula f) -> os::ParamValue { return std::string(to_string(f)); };
  os::ParamTable<P> p;
  p.add("formula", &P::formula, std::move(formula))
      .range(1.0, 32.0)
      .doc("floreano_mondada, one_plus_one (Nolfi's) or liolib (docs/evolution.md)")
      .live();
  p.add("reset", &P::reset).doc("true: zero the sum and the step count").live();
  p.add("command_timeout", &P::command_timeout)
      .range(0.0, 3600.0)
      .doc("a wheel command older than this counts as stopped wheels")
      .live();
  p.add("every", &P::every)
      .range(1.0, 1000.0)
      .doc("report after every N-th step: [sum, steps, step] at 1, [sum, steps, window sum, N] above")
      .live();
  auto t =
      os::declare_task_type("fitness",
                            "on-line fitness: IR readings (>= 3 numbers) and wheel commands (2 numbers) in on port 0, "
                            "[sum, steps, step] out on port 0 after every reading (every N-th: see every)",
                            std::move(p), [](const P& o) { return std::make_unique<FitnessTask>(o); });
  t.defaults.priority = 1;
  t.defaults.queue_capacity = 8;
  t.outputs = {{0, "fitness", kFitnessReport}};
  return t;
}

// The one_plus_one type's parameters: the task's options and the candidate mlp's shape.
struct OnePlusOneParams : OnePlusOneTaskOptions {
  std::int64_t inputs = 7;
  std::string layers = "2";
  std::string activation = "tanh";
};

os::TaskType one_plus_one_type() {
  using P = OnePlusOneParams;
  using A = OnePlusOneOptions;
  using S = ControllerSwapOptions;
  os::ParamTable<P> p;
  p.add("evaluation", &P::swap, &S::evaluation).range(0.001, 86400.0).doc("counted time per candidate");
  p.add("recovery", &P::swap, &S::recovery).range(0.0, 3600.0).doc("uncounted time before it, after a swap");
  p.add("genes", &P::algorithm, &A::genes)
      .range(1.0, 20000.0)
      .doc("genome length: must be the mlp's genome size ((inputs + 1) x outputs for a perceptron)");
  p.add("inputs", &P::inputs)
      .range(1.0, static_cast<double>(control::network::kMaxInputs))
      .doc("the candidate mlp's input count");
  p.add("layers", &P::layers).range(1.0, 200.0).doc("the candidate mlp's hidden then output sizes");
  p.add("activation", &P::activation).range(1.0, 16.0).doc("the candidate mlp's activation");
  p.add("lo", &P::algorithm, &A::lo).range(-1e6, 1e6).doc("lowest gene value");
  p.add("hi", &P::algorithm, &A::hi).range(-1e6, 1e6).doc("highest gene value");
  p.add("sigma", &P::algorithm, &A::sigma).range(1e-12, 1e6).doc("initial mutation step size");
  p.add("sigma_min", &P::algorithm, &A::sigma_min).range(1e-12, 1e6).doc("step size after a success");
  p.add("sigma_max", &P::algorithm, &A::sigma_max).range(1e-12, 1e6).doc("step size ceiling (doubled after a failure)");
  p.add("reevaluation", &P::algorithm, &A::reevaluation)
      .range(0.0, 1.0)
      .doc("probability of re-running the champion after a failed challenger");
  p.add("controller", &P::swap, &S::controller).range(1.0, 63.0).doc("the name of the controller task it replaces");
  p.add("sensor", &P::swap, &S::sensor).range(1.0, 63.0).doc("the task hooked into each candidate");
  p.add("actuator", &P::swap, &S::actuator).range(1.0, 63.0).doc("the task each candidate drives");
  p.add("fitness", &P::swap, &S::fitness).range(1.0, 63.0).doc("the fitness task it reads");
  auto t = os::declare_task_type(
      "one_plus_one",
      "(1+1)-ONLINE evolution: replaces the controller task by a new mlp per candidate, reads the "
      "fitness task's [sum, steps, step]",
      std::move(p), [](const P& c) -> Result<std::unique_ptr<OnePlusOneTask>> {
        if (auto st = check_mlp_genes(c.algorithm.genes, c.inputs, c.layers, c.activation); !st)
          return Error{st.error()};
        OnePlusOneTaskOptions o = c;
        o.swap.controller_type = "mlp";
        o.swap.controller_params = mlp_params_text(c.inputs, c.layers, c.activation);
        return OnePlusOneTask::create(std::move(o));
      });
  t.defaults.priority = 1;
  t.defaults.period = 1s;
  t.defaults.queue_capacity = 8;
  return t;
}

}  // namespace

kernel::Status register_evo_task_types(os::TaskTypeRegistry& registry, const control::ControlResources& /*resources*/) {
  if (auto st = registry.add(fitness_type()); !st) return st;
  if (auto st = register_arbiter_task_type(registry); !st) return st;
  if (auto st = register_mu_plus_one_task_types(registry); !st) return st;
  if (auto st = register_medea_task_types(registry); !st) return st;
  return registry.add(one_plus_one_type());
}

}  // namespace symb::evo
