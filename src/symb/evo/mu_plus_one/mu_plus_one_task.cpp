#include "symb/evo/mu_plus_one/mu_plus_one_task.hpp"

#include <utility>

#include "symb/os/node.hpp"
#include "symb/os/param.hpp"

namespace symb::evo {

namespace {

using namespace std::chrono_literals;

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
  if (m.port == kImmigrantPort && !m.payload.blob) {
    const auto genes = m.numbers();
    if (!algorithm_ || genes.size() != options_.algorithm.genes) {
      log(os::LogLevel::kWarn, "mu_plus_one: ignored a migrant of " + std::to_string(genes.size()) + " genes (" +
                                   std::to_string(options_.algorithm.genes) + " expected)");
      return;
    }
    RealGenome g;
    g.values.assign(genes.begin(), genes.end());
    algorithm_->immigrate(std::move(g));
    return;
  }
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
  if (kind == MuCandidate::kChild && a.counts().immigrants > 0)
    probe("immigrants", {static_cast<float>(a.counts().immigrants), static_cast<float>(a.counts().immigrants_taken)});
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

// The mu_plus_one type's parameters: the task's options and the candidate mlp's shape.
struct MuPlusOneParams : MuPlusOneTaskOptions {
  std::int64_t inputs = 7;
  std::string layers = "2";
  std::string activation = "tanh";
};

// A word standing for one of two values.
template <class T>
os::ParamCodec<T> either(std::string name, std::string a, T va, std::string b, T vb) {
  os::ParamCodec<T> c;
  c.type = os::ParamType::kString;
  c.parse = [=](const os::ParamValue& v) -> kernel::Result<T> {
    const auto& w = std::get<std::string>(v);
    if (w == a) return va;
    if (w == b) return vb;
    return kernel::Error{name + ": '" + w + "' is neither " + a + " nor " + b};
  };
  c.format = [=](T x) -> os::ParamValue { return x == va ? a : b; };
  return c;
}

os::TaskType mu_plus_one_type() {
  using P = MuPlusOneParams;
  using A = MuPlusOneOptions;
  using S = ControllerSwapOptions;
  os::ParamTable<P> p;
  p.add("mu", &P::algorithm, &A::mu).range(2.0, 10000.0).doc("population size");
  p.add("rho", &P::algorithm, &A::rho).range(0.0, 0.999).doc("re-evaluation probability per step");
  p.add("sigma", &P::algorithm, &A::sigma).range(1e-12, 1e6).doc("Gaussian mutation step size (fixed)");
  p.add("crossover", &P::algorithm, &A::crossover).range(0.0, 1.0).doc("probability of a uniform crossover");
  p.add("selection", &P::algorithm, &A::selection,
        either("selection", "tournament", ParentSelection::kBinaryTournament, "uniform", ParentSelection::kUniform))
      .range(1.0, 16.0)
      .doc("parent selection: tournament (binary) or uniform");
  p.add("reevaluation", &P::algorithm, &A::reevaluation,
        either("reevaluation", "average", Reevaluation::kAverage, "replace", Reevaluation::kReplace))
      .range(1.0, 16.0)
      .doc("a re-evaluated member's fitness: average (of all its runs) or replace (the newest)");
  p.add("evaluation", &P::swap, &S::evaluation).range(0.001, 86400.0).doc("counted time per candidate (tau)");
  p.add("recovery", &P::swap, &S::recovery).range(0.0, 3600.0).doc("uncounted time before it, after a swap");
  p.add("genes", &P::algorithm, &A::genes)
      .range(1.0, 20000.0)
      .doc("genome length: must be the mlp's genome size ((inputs + 1) x outputs for a perceptron)");
  p.add("inputs", &P::inputs).range(1.0, 1000.0).doc("the candidate mlp's input count");
  p.add("layers", &P::layers).range(1.0, 200.0).doc("the candidate mlp's hidden then output sizes");
  p.add("activation", &P::activation).range(1.0, 16.0).doc("the candidate mlp's activation");
  p.add("lo", &P::algorithm, &A::lo).range(-1e6, 1e6).doc("lowest gene value");
  p.add("hi", &P::algorithm, &A::hi).range(-1e6, 1e6).doc("highest gene value");
  p.add("controller", &P::swap, &S::controller).range(1.0, 63.0).doc("the name of the controller task it replaces");
  p.add("sensor", &P::swap, &S::sensor).range(1.0, 63.0).doc("the task hooked into each candidate");
  p.add("actuator", &P::swap, &S::actuator).range(1.0, 63.0).doc("the task each candidate drives");
  p.add("fitness", &P::swap, &S::fitness).range(1.0, 63.0).doc("the fitness task it reads");
  auto t = os::declare_task_type(
      "mu_plus_one",
      "encapsulated (mu+1)-ONLINE evolution: a population of mu genomes on the robot; replaces the "
      "controller task by a new mlp per candidate, reads the fitness task's [sum, steps, step]",
      std::move(p), [](const P& c) -> kernel::Result<std::unique_ptr<MuPlusOneTask>> {
        if (auto st = check_mlp_genes(c.algorithm.genes, c.inputs, c.layers, c.activation); !st)
          return kernel::Error{st.error()};
        MuPlusOneTaskOptions o = c;
        o.swap.controller_type = "mlp";
        o.swap.controller_params = mlp_params_text(c.inputs, c.layers, c.activation);
        return MuPlusOneTask::create(std::move(o));
      });
  t.defaults.priority = 1;
  t.defaults.period = 1s;
  t.defaults.queue_capacity = 8;
  return t;
}

}  // namespace

kernel::Status register_mu_plus_one_task_types(os::TaskTypeRegistry& registry) {
  return registry.add(mu_plus_one_type());
}

}  // namespace symb::evo
