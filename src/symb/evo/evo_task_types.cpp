#include "symb/evo/evo_task_types.hpp"

#include <memory>
#include <stdexcept>
#include <string>

#include "symb/control/network/network.hpp"
#include "symb/evo/arbiter_task.hpp"
#include "symb/evo/controller_swap.hpp"
#include "symb/evo/fitness_task.hpp"
#include "symb/evo/medea_task.hpp"
#include "symb/evo/mu_plus_one_task.hpp"
#include "symb/evo/one_plus_one_task.hpp"

namespace symb::evo {

namespace {

using namespace std::chrono_literals;
using os::ParamSpec;
using os::ParamType;

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument(what); }

os::TaskType fitness_type() {
  os::TaskType t;
  t.name = "fitness";
  t.doc =
      "on-line fitness: IR readings (>= 3 numbers) and wheel commands (2 numbers) in on port 0, "
      "[sum, steps, step] out on port 0 after every reading (every N-th: see every)";
  const FitnessTaskOptions d;
  t.params = {
      {"formula", ParamType::kString, std::string(to_string(d.formula)), 1.0, 32.0,
       "floreano_mondada, one_plus_one (Nolfi's) or liolib (docs/evolution.md)"},
      {"reset", ParamType::kBool, false, std::nullopt, std::nullopt, "true: zero the sum and the step count"},
      {"command_timeout", ParamType::kDuration, d.command_timeout, 0.0, 3600.0,
       "a wheel command older than this counts as stopped wheels"},
      {"every", ParamType::kInt, static_cast<std::int64_t>(d.every), 1.0, 1000.0,
       "report after every N-th step: [sum, steps, step] at 1, [sum, steps, window sum, N] above"},
  };
  t.defaults.priority = 1;
  t.defaults.queue_capacity = 8;
  t.make = [](const os::ParamSet& p) -> std::unique_ptr<os::Task> {
    FitnessTaskOptions o;
    const auto f = parse_fitness_formula(p.string("formula"));
    if (!f) fail("formula: '" + p.string("formula") + "' is none of floreano_mondada, one_plus_one, liolib");
    o.formula = *f;
    o.command_timeout = p.duration("command_timeout");
    o.every = static_cast<std::uint32_t>(p.integer("every"));
    return std::make_unique<FitnessTask>(o);
  };
  return t;
}

std::size_t mlp_genome_size(const os::ParamSet& p) {
  auto n = evo::mlp_genome_size(p.integer("inputs"), p.string("layers"), p.string("activation"));
  if (!n) fail(n.error());
  return *n;
}

os::TaskType one_plus_one_type() {
  os::TaskType t;
  t.name = "one_plus_one";
  t.doc =
      "(1+1)-ONLINE evolution: replaces the controller task by a new mlp per candidate, reads the "
      "fitness task's [sum, steps, step]";
  const OnePlusOneTaskOptions d;
  const OnePlusOneOptions& a = d.algorithm;
  t.params = {
      {"evaluation", ParamType::kDuration, d.evaluation, 0.001, 86400.0, "counted time per candidate"},
      {"recovery", ParamType::kDuration, d.recovery, 0.0, 3600.0, "uncounted time before it, after a swap"},
      {"genes", ParamType::kInt, static_cast<std::int64_t>(a.genes), 1.0, 20000.0,
       "genome length: must be the mlp's genome size ((inputs + 1) x outputs for a perceptron)"},
      {"inputs", ParamType::kInt, std::int64_t{7}, 1.0, static_cast<double>(control::network::kMaxInputs),
       "the candidate mlp's input count"},
      {"layers", ParamType::kString, std::string("2"), 1.0, 200.0, "the candidate mlp's hidden then output sizes"},
      {"activation", ParamType::kString, std::string("tanh"), 1.0, 16.0, "the candidate mlp's activation"},
      {"lo", ParamType::kReal, a.lo, -1e6, 1e6, "lowest gene value"},
      {"hi", ParamType::kReal, a.hi, -1e6, 1e6, "highest gene value"},
      {"sigma", ParamType::kReal, a.sigma, 1e-12, 1e6, "initial mutation step size"},
      {"sigma_min", ParamType::kReal, a.sigma_min, 1e-12, 1e6, "step size after a success"},
      {"sigma_max", ParamType::kReal, a.sigma_max, 1e-12, 1e6, "step size ceiling (doubled after a failure)"},
      {"reevaluation", ParamType::kReal, a.reevaluation, 0.0, 1.0,
       "probability of re-running the champion after a failed challenger"},
      {"controller", ParamType::kString, d.controller, 1.0, 63.0, "the name of the controller task it replaces"},
      {"sensor", ParamType::kString, d.sensor, 1.0, 63.0, "the task hooked into each candidate"},
      {"actuator", ParamType::kString, d.actuator, 1.0, 63.0, "the task each candidate drives"},
      {"fitness", ParamType::kString, d.fitness, 1.0, 63.0, "the fitness task it reads"},
  };
  t.defaults.priority = 1;
  t.defaults.period = 1s;
  t.defaults.queue_capacity = 8;
  t.make = [](const os::ParamSet& p) -> std::unique_ptr<os::Task> {
    OnePlusOneTaskOptions o;
    o.evaluation = p.duration("evaluation");
    o.recovery = p.duration("recovery");
    o.algorithm.genes = static_cast<std::size_t>(p.integer("genes"));
    const std::size_t needed = mlp_genome_size(p);
    if (o.algorithm.genes != needed)
      fail("genes: " + std::to_string(o.algorithm.genes) +
           " genes, but the mlp (inputs=" + std::to_string(p.integer("inputs")) + " layers=\"" + p.string("layers") +
           "\") has " + std::to_string(needed) + " weights and biases");
    o.algorithm.lo = p.real("lo");
    o.algorithm.hi = p.real("hi");
    o.algorithm.sigma = p.real("sigma");
    o.algorithm.sigma_min = p.real("sigma_min");
    o.algorithm.sigma_max = p.real("sigma_max");
    o.algorithm.reevaluation = p.real("reevaluation");
    o.controller_type = "mlp";
    o.controller_params = "inputs=" + std::to_string(p.integer("inputs")) + " layers=\"" + p.string("layers") +
                          "\" activation=" + p.string("activation");
    o.controller = p.string("controller");
    o.sensor = p.string("sensor");
    o.actuator = p.string("actuator");
    o.fitness = p.string("fitness");
    auto task = OnePlusOneTask::create(std::move(o));
    if (!task) fail(task.error());
    return std::move(task).value();
  };
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
