#include "symb/evo/mu_plus_one_task.hpp"

#include <stdexcept>
#include <utility>

#include "symb/os/node.hpp"
#include "symb/os/param.hpp"

namespace symb::evo {

namespace {

using namespace std::chrono_literals;

constexpr std::size_t kHistoryLimit = 1 << 16;  // evaluations kept for history() (days of driving)

}  // namespace

kernel::Result<std::unique_ptr<MuPlusOneTask>> MuPlusOneTask::create(MuPlusOneTaskOptions options) {
  if (auto st = check(options.algorithm); !st) return kernel::Error{st.error()};
  if (auto st = check(options.swap, "mu_plus_one"); !st) return kernel::Error{st.error()};
  return std::unique_ptr<MuPlusOneTask>(new MuPlusOneTask(std::move(options)));
}

EvolutionState MuPlusOneTask::state() const {
  std::lock_guard lock(mu_);
  return state_;
}
std::string MuPlusOneTask::error() const {
  std::lock_guard lock(mu_);
  return error_;
}
std::optional<Member> MuPlusOneTask::best() const {
  std::lock_guard lock(mu_);
  return best_;
}
std::vector<Member> MuPlusOneTask::population() const {
  std::lock_guard lock(mu_);
  return population_;
}
MuPlusOneCounts MuPlusOneTask::counts() const {
  std::lock_guard lock(mu_);
  return counts_;
}
std::vector<MuEvaluationRecord> MuPlusOneTask::history() const {
  std::lock_guard lock(mu_);
  return history_;
}
std::uint64_t MuPlusOneTask::controllers_created() const {
  std::lock_guard lock(mu_);
  return created_;
}

void MuPlusOneTask::fail(const std::string& why) {
  log(os::LogLevel::kError, why);
  std::lock_guard lock(mu_);
  state_ = EvolutionState::kFailed;
  error_ = why;
}

void MuPlusOneTask::on_start() {
  // A stream of its own, drawn from the task's: same node seed and task name, same evolution.
  const std::uint64_t seed = random().next_u64();
  const std::uint64_t stream = random().next_u64();  // two statements: a fixed order on every compiler
  auto a = MuPlusOne::create(options_.algorithm, kernel::RandomStream(seed, stream));
  if (!a) {
    fail(a.error());
    return;
  }
  algorithm_.emplace(std::move(a).value());
  if (set_up()) start_candidate();
}

void MuPlusOneTask::on_tick() {
  if (state() == EvolutionState::kWaiting && algorithm_ && set_up()) start_candidate();
}

bool MuPlusOneTask::set_up() {
  auto ready = swap_.set_up(node(), id());
  if (!ready) {
    fail(ready.error());
    return false;
  }
  if (!*ready) {
    const ControllerSwapOptions& o = options_.swap;
    if (!warned_missing_)
      log(os::LogLevel::kWarn,
          "mu_plus_one: waiting for the tasks '" + o.sensor + "', '" + o.actuator + "' and '" + o.fitness + "'");
    warned_missing_ = true;
    return false;
  }
  std::lock_guard lock(mu_);
  state_ = EvolutionState::kRunning;
  return true;
}

void MuPlusOneTask::start_candidate() {
  if (auto st = swap_.swap(node(), algorithm_->next(), now()); !st) {
    fail(st.error());
    return;
  }
  std::lock_guard lock(mu_);
  ++created_;
}

void MuPlusOneTask::on_message(const os::Message& m) {
  if (state() != EvolutionState::kRunning) return;
  if (auto fitness = swap_.feed(m, now())) finish_evaluation(*fitness);
}

void MuPlusOneTask::finish_evaluation(double fitness) {
  const MuCandidate kind = algorithm_->candidate_kind();
  const std::uint64_t replacements_before = algorithm_->counts().replacements;
  algorithm_->report(fitness);
  const MuPlusOne& a = *algorithm_;
  if (a.counts().replacements > replacements_before)
    log(os::LogLevel::kDebug, "mu_plus_one: a child replaced the worst member, fitness " + std::to_string(fitness));
  const Member& best = a.best();
  const double mean = a.mean_fitness();
  {
    std::lock_guard lock(mu_);
    population_ = a.population();
    best_ = best;
    counts_ = a.counts();
    if (history_.size() < kHistoryLimit)
      history_.push_back({now(), kind, fitness, best.fitness, mean, swap_.counted_steps()});
  }
  probe("fitness", {static_cast<float>(fitness), static_cast<float>(static_cast<int>(kind))});
  probe("best_fitness", {static_cast<float>(best.fitness)});
  probe("mean_fitness", {static_cast<float>(mean)});
  probe("evaluations", {static_cast<float>(a.counts().evaluations)});
  // The best member's genes whenever another genome becomes the best (as floats: what the mlp
  // drove with), so whoever watches the run (symb evolve) can save it.
  if (probing() && best.genome.values != probed_best_) {
    probed_best_ = best.genome.values;
    std::vector<float> genes(probed_best_.begin(), probed_best_.end());
    probe("champion", genes);
  }
  start_candidate();
}

namespace {

using os::ParamType;

[[noreturn]] void fail_make(const std::string& what) { throw std::invalid_argument(what); }

os::TaskType mu_plus_one_type() {
  os::TaskType t;
  t.name = "mu_plus_one";
  t.doc =
      "encapsulated (mu+1)-ONLINE evolution: a population of mu genomes on the robot; replaces the "
      "controller task by a new mlp per candidate, reads the fitness task's [sum, steps, step]";
  const MuPlusOneTaskOptions d;
  const MuPlusOneOptions& a = d.algorithm;
  t.params = {
      {"mu", ParamType::kInt, static_cast<std::int64_t>(a.mu), 2.0, 10000.0, "population size"},
      {"rho", ParamType::kReal, a.rho, 0.0, 0.999, "re-evaluation probability per step"},
      {"sigma", ParamType::kReal, a.sigma, 1e-12, 1e6, "Gaussian mutation step size (fixed)"},
      {"crossover", ParamType::kReal, a.crossover, 0.0, 1.0, "probability of a uniform crossover"},
      {"selection", ParamType::kString, std::string("tournament"), 1.0, 16.0,
       "parent selection: tournament (binary) or uniform"},
      {"reevaluation", ParamType::kString, std::string("average"), 1.0, 16.0,
       "a re-evaluated member's fitness: average (of all its runs) or replace (the newest)"},
      {"evaluation", ParamType::kDuration, d.swap.evaluation, 0.001, 86400.0, "counted time per candidate (tau)"},
      {"recovery", ParamType::kDuration, d.swap.recovery, 0.0, 3600.0, "uncounted time before it, after a swap"},
      {"genes", ParamType::kInt, static_cast<std::int64_t>(a.genes), 1.0, 20000.0,
       "genome length: must be the mlp's genome size ((inputs + 1) x outputs for a perceptron)"},
      {"inputs", ParamType::kInt, std::int64_t{7}, 1.0, 1000.0, "the candidate mlp's input count"},
      {"layers", ParamType::kString, std::string("2"), 1.0, 200.0, "the candidate mlp's hidden then output sizes"},
      {"activation", ParamType::kString, std::string("tanh"), 1.0, 16.0, "the candidate mlp's activation"},
      {"lo", ParamType::kReal, a.lo, -1e6, 1e6, "lowest gene value"},
      {"hi", ParamType::kReal, a.hi, -1e6, 1e6, "highest gene value"},
      {"controller", ParamType::kString, d.swap.controller, 1.0, 63.0, "the name of the controller task it replaces"},
      {"sensor", ParamType::kString, d.swap.sensor, 1.0, 63.0, "the task hooked into each candidate"},
      {"actuator", ParamType::kString, d.swap.actuator, 1.0, 63.0, "the task each candidate drives"},
      {"fitness", ParamType::kString, d.swap.fitness, 1.0, 63.0, "the fitness task it reads"},
  };
  t.defaults.priority = 1;
  t.defaults.period = 1s;
  t.defaults.queue_capacity = 8;
  t.make = [](const os::ParamSet& p) -> std::unique_ptr<os::Task> {
    MuPlusOneTaskOptions o;
    MuPlusOneOptions& alg = o.algorithm;
    alg.mu = static_cast<std::size_t>(p.integer("mu"));
    alg.rho = p.real("rho");
    alg.sigma = p.real("sigma");
    alg.crossover = p.real("crossover");
    const std::string selection = p.string("selection"), reevaluation = p.string("reevaluation");
    if (selection == "tournament")
      alg.selection = ParentSelection::kBinaryTournament;
    else if (selection == "uniform")
      alg.selection = ParentSelection::kUniform;
    else
      fail_make("selection: '" + selection + "' is neither tournament nor uniform");
    if (reevaluation == "average")
      alg.reevaluation = Reevaluation::kAverage;
    else if (reevaluation == "replace")
      alg.reevaluation = Reevaluation::kReplace;
    else
      fail_make("reevaluation: '" + reevaluation + "' is neither average nor replace");
    alg.genes = static_cast<std::size_t>(p.integer("genes"));
    auto needed = mlp_genome_size(p.integer("inputs"), p.string("layers"), p.string("activation"));
    if (!needed) fail_make(needed.error());
    if (alg.genes != *needed)
      fail_make("genes: " + std::to_string(alg.genes) +
                " genes, but the mlp (inputs=" + std::to_string(p.integer("inputs")) + " layers=\"" +
                p.string("layers") + "\") has " + std::to_string(*needed) + " weights and biases");
    alg.lo = p.real("lo");
    alg.hi = p.real("hi");
    o.swap.evaluation = p.duration("evaluation");
    o.swap.recovery = p.duration("recovery");
    o.swap.controller_type = "mlp";
    o.swap.controller_params = "inputs=" + std::to_string(p.integer("inputs")) + " layers=\"" + p.string("layers") +
                               "\" activation=" + p.string("activation");
    o.swap.controller = p.string("controller");
    o.swap.sensor = p.string("sensor");
    o.swap.actuator = p.string("actuator");
    o.swap.fitness = p.string("fitness");
    auto task = MuPlusOneTask::create(std::move(o));
    if (!task) fail_make(task.error());
    return std::move(task).value();
  };
  return t;
}

}  // namespace

kernel::Status register_mu_plus_one_task_types(os::TaskTypeRegistry& registry) {
  return registry.add(mu_plus_one_type());
}

}  // namespace symb::evo
