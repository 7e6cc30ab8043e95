#include "symb/evo/one_plus_one_task.hpp"

#include <cmath>
#include <utility>

#include "symb/os/node.hpp"
#include "symb/os/param.hpp"

namespace symb::evo {

namespace {

constexpr std::size_t kHistoryLimit = 1 << 16;  // evaluations kept for history() (days of driving)

}  // namespace

kernel::Result<std::unique_ptr<OnePlusOneTask>> OnePlusOneTask::create(OnePlusOneTaskOptions options) {
  if (auto st = check(options.algorithm); !st) return kernel::Error{st.error()};
  if (options.evaluation.count() <= 0) return kernel::Error{"one_plus_one: evaluation must be positive"};
  if (options.recovery.count() < 0) return kernel::Error{"one_plus_one: recovery must not be negative"};
  for (const std::string* n : {&options.controller, &options.sensor, &options.actuator, &options.fitness})
    if (!os::is_valid_name(*n)) return kernel::Error{"one_plus_one: '" + *n + "' cannot name a task"};
  if (!os::is_valid_name(options.controller_type))
    return kernel::Error{"one_plus_one: '" + options.controller_type + "' cannot name a task type"};
  auto params = os::parse_param_assignments(options.controller_params);
  if (!params) return kernel::Error{"one_plus_one: controller parameters: " + params.error()};
  for (const auto& a : *params)
    if (a.name == "weights") return kernel::Error{"one_plus_one: controller parameters: weights are the genome's"};
  return std::unique_ptr<OnePlusOneTask>(new OnePlusOneTask(std::move(options)));
}

EvolutionState OnePlusOneTask::state() const {
  std::lock_guard lock(mu_);
  return state_;
}
std::string OnePlusOneTask::error() const {
  std::lock_guard lock(mu_);
  return error_;
}
std::optional<RealGenome> OnePlusOneTask::champion() const {
  std::lock_guard lock(mu_);
  return champion_;
}
double OnePlusOneTask::champion_fitness() const {
  std::lock_guard lock(mu_);
  return champion_fitness_;
}
OnePlusOneCounts OnePlusOneTask::counts() const {
  std::lock_guard lock(mu_);
  return counts_;
}
std::vector<EvaluationRecord> OnePlusOneTask::history() const {
  std::lock_guard lock(mu_);
  return history_;
}
std::uint64_t OnePlusOneTask::controllers_created() const {
  std::lock_guard lock(mu_);
  return created_;
}

void OnePlusOneTask::fail(const std::string& why) {
  log(os::LogLevel::kError, why);
  std::lock_guard lock(mu_);
  state_ = EvolutionState::kFailed;
  error_ = why;
}

void OnePlusOneTask::on_start() {
  // A stream of its own, drawn from the task's: same node seed and task name, same evolution.
  const std::uint64_t seed = random().next_u64();
  const std::uint64_t stream = random().next_u64();  // two statements: a fixed order on every compiler
  auto a = OnePlusOne::create(options_.algorithm, kernel::RandomStream(seed, stream));
  if (!a) {
    fail(a.error());
    return;
  }
  algorithm_.emplace(std::move(a).value());
  if (set_up()) start_candidate();
}

void OnePlusOneTask::on_tick() {
  if (state() == EvolutionState::kWaiting && algorithm_ && set_up()) start_candidate();
}

// Finds the tasks evolution works with and hooks the fitness task to this one.
bool OnePlusOneTask::set_up() {
  os::Node& n = node();
  const auto sensor = n.find(options_.sensor), actuator = n.find(options_.actuator), fitness = n.find(options_.fitness);
  if (!sensor || !actuator || !fitness) {
    if (!warned_missing_)
      log(os::LogLevel::kWarn, "one_plus_one: waiting for the tasks '" + options_.sensor + "', '" + options_.actuator +
                                   "' and '" + options_.fitness + "'");
    warned_missing_ = true;
    return false;
  }
  if (auto h = n.hook(*fitness, id()); !h) {
    fail("one_plus_one: cannot hook '" + options_.fitness + "': " + h.error());
    return false;
  }
  sensor_ = *sensor, actuator_ = *actuator, fitness_ = *fitness;
  {
    std::lock_guard lock(mu_);
    state_ = EvolutionState::kRunning;
  }
  return true;
}

// Replaces the controller task by a new one running algorithm_->next().
void OnePlusOneTask::start_candidate() {
  os::Node& n = node();
  if (have_controller_) {
    (void)n.remove(controller_);  // gone already (removed by someone else) is fine
    have_controller_ = false;
  } else if (auto existing = n.find(options_.controller)) {
    (void)n.remove(*existing);  // the scenario's own controller: the first candidate replaces it
  }
  auto params = os::parse_param_assignments(options_.controller_params);
  if (!params) {
    fail("one_plus_one: controller parameters: " + params.error());
    return;
  }
  std::vector<os::ParamAssignment> assignments = std::move(params).value();
  assignments.push_back({"weights", weights_text(algorithm_->next()), 1});
  auto created = n.create(options_.controller_type, options_.controller, assignments);
  if (!created) {
    fail("one_plus_one: cannot create the candidate controller: " + created.error());
    return;
  }
  controller_ = *created;
  have_controller_ = true;
  for (auto [from, to] :
       {std::pair{sensor_, controller_}, std::pair{controller_, actuator_}, std::pair{controller_, fitness_}}) {
    if (auto h = n.hook(from, to); !h) {
      fail("one_plus_one: cannot hook the candidate controller: " + h.error());
      return;
    }
  }
  started_ = now();
  counted_sum_ = 0;
  counted_steps_ = 0;
  std::lock_guard lock(mu_);
  ++created_;
}

void OnePlusOneTask::on_message(const os::Message& m) {
  if (state() != EvolutionState::kRunning || !have_controller_ || m.source != fitness_) return;
  const auto v = m.numbers();
  if (v.size() < 2 || !std::isfinite(v[0])) return;
  const double step = v.size() >= 3 ? static_cast<double>(v[2]) : static_cast<double>(v[0]) - last_sum_;
  last_sum_ = v[0];
  const kernel::Time t = now();
  if (t < started_ + options_.recovery) return;  // recovery: not counted
  if (std::isfinite(step)) {
    counted_sum_ += step;
    ++counted_steps_;
  }
  if (t >= started_ + options_.recovery + options_.evaluation) finish_evaluation();
}

void OnePlusOneTask::finish_evaluation() {
  const double fitness = counted_steps_ == 0 ? 0.0 : counted_sum_ / static_cast<double>(counted_steps_);
  const Candidate kind = algorithm_->candidate_kind();
  const std::uint64_t successes_before = algorithm_->counts().successes;
  algorithm_->report(fitness);
  const OnePlusOne& a = *algorithm_;
  if (a.counts().successes > successes_before)
    log(os::LogLevel::kInfo, "one_plus_one: new champion, fitness " + std::to_string(fitness));
  {
    std::lock_guard lock(mu_);
    champion_ = a.champion();
    champion_fitness_ = a.champion_fitness();
    counts_ = a.counts();
    if (history_.size() < kHistoryLimit)
      history_.push_back({now(), kind, fitness, a.champion_fitness(), a.sigma(), counted_steps_});
  }
  probe("fitness", {static_cast<float>(fitness), static_cast<float>(static_cast<int>(kind))});
  probe("champion_fitness", {static_cast<float>(a.champion_fitness())});
  probe("sigma", {static_cast<float>(a.sigma())});
  probe("evaluations", {static_cast<float>(a.counts().evaluations)});
  // The champion's genes whenever it changes (as floats: what the mlp drove with), so whoever
  // watches the run (symb evolve) can save it.
  if (probing() && (kind == Candidate::kFirst || a.counts().successes > successes_before)) {
    std::vector<float> genes(a.champion().values.begin(), a.champion().values.end());
    probe("champion", genes);
  }
  start_candidate();
}

}  // namespace symb::evo
