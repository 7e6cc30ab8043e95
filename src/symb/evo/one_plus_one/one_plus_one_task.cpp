#include "symb/evo/one_plus_one/one_plus_one_task.hpp"

#include <cmath>
#include <utility>

#include "symb/os/node.hpp"
#include "symb/os/param.hpp"

namespace symb::evo {

kernel::Result<std::unique_ptr<OnePlusOneTask>> OnePlusOneTask::create(OnePlusOneTaskOptions options) {
  if (auto st = check(options.algorithm); !st) return kernel::Error{st.error()};
  if (auto st = check(options.swap, "one_plus_one"); !st) return kernel::Error{st.error()};
  return std::unique_ptr<OnePlusOneTask>(new OnePlusOneTask(std::move(options)));
}

OnePlusOneTask::OnePlusOneTask(OnePlusOneTaskOptions options)
    : options_(std::move(options)), swap_(options_.swap, "one_plus_one") {}

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
  auto ready = swap_.set_up(node(), id());
  if (!ready) {
    fail(ready.error());
    return false;
  }
  if (!*ready) {
    if (!warned_missing_)
      log(os::LogLevel::kWarn, "one_plus_one: waiting for the tasks '" + options_.swap.sensor + "', '" +
                                   options_.swap.actuator + "' and '" + options_.swap.fitness + "'");
    warned_missing_ = true;
    return false;
  }
  std::lock_guard lock(mu_);
  state_ = EvolutionState::kRunning;
  return true;
}

// Replaces the controller task by a new one running algorithm_->next().
void OnePlusOneTask::start_candidate() {
  if (auto st = swap_.swap(node(), algorithm_->next(), now()); !st) {
    fail(st.error());
    return;
  }
  std::lock_guard lock(mu_);
  ++created_;
}

void OnePlusOneTask::on_message(const os::Message& m) {
  if (m.port == kImmigrantPort && !m.payload.blob) {
    const auto genes = m.numbers();
    if (!algorithm_ || genes.size() != options_.algorithm.genes) {
      log(os::LogLevel::kWarn, "one_plus_one: ignored a migrant of " + std::to_string(genes.size()) + " genes (" +
                                   std::to_string(options_.algorithm.genes) + " expected)");
      return;
    }
    RealGenome g = algorithm_->champion();
    g.values.assign(genes.begin(), genes.end());
    algorithm_->immigrate(std::move(g));
    return;
  }
  if (state() != EvolutionState::kRunning) return;
  if (auto fitness = swap_.feed(m, now())) finish_evaluation(*fitness);
}

void OnePlusOneTask::finish_evaluation(double fitness) {
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
      history_.push_back({now(), kind, fitness, a.champion_fitness(), a.sigma(), swap_.counted_steps()});
  }
  probe("fitness", {static_cast<float>(fitness), static_cast<float>(static_cast<int>(kind))});
  probe("champion_fitness", {static_cast<float>(a.champion_fitness())});
  probe("sigma", {static_cast<float>(a.sigma())});
  probe("evaluations", {static_cast<float>(a.counts().evaluations)});
  if (kind == Candidate::kChallenger && a.counts().immigrants > 0)
    probe("immigrants", {static_cast<float>(a.counts().immigrants), static_cast<float>(a.counts().immigrants_taken)});
  // The champion's genes whenever it changes (as floats: what the mlp drove with), so whoever
  // watches the run (symb evolve) can save it.
  if (probing() && (kind == Candidate::kFirst || a.counts().successes > successes_before)) {
    std::vector<float> genes(a.champion().values.begin(), a.champion().values.end());
    probe("champion", genes);
  }
  start_candidate();
}

}  // namespace symb::evo
