#include "symb/evo/medea_task.hpp"

#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

#include "symb/control/network/network.hpp"
#include "symb/evo/controller_swap.hpp"
#include "symb/evo/genome.hpp"
#include "symb/io/bytes.hpp"
#include "symb/os/node.hpp"
#include "symb/os/param.hpp"

namespace symb::evo {

namespace {

// The key of a sender whose messages carry no robot index: all such senders share one entry.
constexpr std::uint64_t kUnknownSender = ~std::uint64_t{0};

}  // namespace

kernel::Result<std::unique_ptr<MedeaTask>> MedeaTask::create(MedeaTaskOptions options) {
  if (auto st = check(options.algorithm); !st) return kernel::Error{st.error()};
  if (options.lifetime.count() <= 0) return kernel::Error{"medea: lifetime must be positive"};
  for (const std::string* n : {&options.controller, &options.sensor, &options.actuator, &options.radio})
    if (!os::is_valid_name(*n)) return kernel::Error{"medea: '" + *n + "' cannot name a task"};
  if (!os::is_valid_name(options.controller_type))
    return kernel::Error{"medea: '" + options.controller_type + "' cannot name a task type"};
  auto params = os::parse_param_assignments(options.controller_params);
  if (!params) return kernel::Error{"medea: controller parameters: " + params.error()};
  for (const auto& a : *params)
    if (a.name == "weights") return kernel::Error{"medea: controller parameters: weights are the genome's"};
  return std::unique_ptr<MedeaTask>(new MedeaTask(std::move(options)));
}

EvolutionState MedeaTask::state() const {
  std::lock_guard lock(mu_);
  return state_;
}
std::string MedeaTask::error() const {
  std::lock_guard lock(mu_);
  return error_;
}
bool MedeaTask::active() const {
  std::lock_guard lock(mu_);
  return active_;
}
RealGenome MedeaTask::genome() const {
  std::lock_guard lock(mu_);
  return genome_;
}
MedeaCounts MedeaTask::counts() const {
  std::lock_guard lock(mu_);
  return counts_;
}
std::uint64_t MedeaTask::controllers_created() const {
  std::lock_guard lock(mu_);
  return created_;
}
std::uint64_t MedeaTask::broadcasts() const {
  std::lock_guard lock(mu_);
  return broadcasts_;
}

void MedeaTask::fail(const std::string& why) {
  log(os::LogLevel::kError, why);
  std::lock_guard lock(mu_);
  state_ = EvolutionState::kFailed;
  error_ = why;
}

void MedeaTask::publish() {
  std::lock_guard lock(mu_);
  active_ = algorithm_->active();
  genome_ = algorithm_->genome();
  counts_ = algorithm_->counts();
}

void MedeaTask::on_start() {
  // A stream of its own, drawn from the task's: same node seed and task name, same evolution.
  const std::uint64_t seed = random().next_u64();
  const std::uint64_t stream = random().next_u64();  // two statements: a fixed order on every compiler
  auto a = Medea::create(options_.algorithm, kernel::RandomStream(seed, stream));
  if (!a) {
    fail(a.error());
    return;
  }
  algorithm_.emplace(std::move(a).value());
  publish();
  if (set_up()) start_lifetime();
}

// Finds the tasks it works with and hooks itself to the radio both ways.
bool MedeaTask::set_up() {
  os::Node& n = node();
  const auto sensor = n.find(options_.sensor), actuator = n.find(options_.actuator), radio = n.find(options_.radio);
  if (!sensor || !actuator || !radio) {
    if (!warned_missing_)
      log(os::LogLevel::kWarn, "medea: waiting for the tasks '" + options_.sensor + "', '" + options_.actuator +
                                   "' and '" + options_.radio + "'");
    warned_missing_ = true;
    return false;
  }
  for (auto [from, to] : {std::pair{*radio, id()}, std::pair{id(), *radio}}) {
    if (auto h = n.hook(from, to); !h) {
      fail("medea: cannot hook the radio '" + options_.radio + "': " + h.error());
      return false;
    }
  }
  sensor_ = *sensor, actuator_ = *actuator, radio_ = *radio;
  std::lock_guard lock(mu_);
  state_ = EvolutionState::kRunning;
  return true;
}

// Replaces the controller task by one running the algorithm's genome, or removes it (inactive).
void MedeaTask::start_lifetime() {
  os::Node& n = node();
  lifetime_start_ = now();
  if (have_controller_) {
    (void)n.remove(controller_);  // gone already (removed by someone else) is fine
    have_controller_ = false;
  } else if (auto existing = n.find(options_.controller)) {
    (void)n.remove(*existing);  // the scenario's own controller: the first genome replaces it
  }
  genome_message_ = {};
  if (!algorithm_->active()) return;  // no controller: the wheels' watchdog stops the robot
  auto params = os::parse_param_assignments(options_.controller_params);
  if (!params) {
    fail("medea: controller parameters: " + params.error());
    return;
  }
  std::vector<os::ParamAssignment> assignments = std::move(params).value();
  assignments.push_back({"weights", weights_text(algorithm_->genome()), 1});
  auto created = n.create(options_.controller_type, options_.controller, assignments);
  if (!created) {
    fail("medea: cannot create the controller: " + created.error());
    return;
  }
  controller_ = *created;
  have_controller_ = true;
  for (auto [from, to] : {std::pair{sensor_, controller_}, std::pair{controller_, actuator_}}) {
    if (auto h = n.hook(from, to); !h) {
      fail("medea: cannot hook the controller: " + h.error());
      return;
    }
  }
  genome_message_ = io::text_payload(to_text(Genome{algorithm_->genome()}));
  {
    std::lock_guard lock(mu_);
    ++created_;
  }
  send(0, genome_message_);  // the first broadcast of the lifetime, at once
  std::lock_guard lock(mu_);
  ++broadcasts_;
}

void MedeaTask::on_tick() {
  const EvolutionState s = state();
  if (s == EvolutionState::kFailed || !algorithm_) return;
  if (s == EvolutionState::kWaiting) {
    if (set_up()) start_lifetime();
    return;
  }
  if (now() >= lifetime_start_ + options_.lifetime) {
    const std::size_t heard = algorithm_->received_count();
    algorithm_->end_of_lifetime();
    publish();
    probe("active", {algorithm_->active() ? 1.0f : 0.0f});
    probe("heard", {static_cast<float>(heard)});
    probe("sigma", {static_cast<float>(algorithm_->genome().sigma)});
    start_lifetime();
    return;
  }
  if (genome_message_.blob) {
    send(0, genome_message_);
    std::lock_guard lock(mu_);
    ++broadcasts_;
  }
}

void MedeaTask::on_message(const os::Message& m) {
  if (!algorithm_ || state() != EvolutionState::kRunning || m.source != radio_) return;
  const io::Bytes* bytes = io::bytes_of(m);
  if (bytes == nullptr) return;
  std::uint64_t sender = kUnknownSender;
  if (const auto v = m.numbers(); !v.empty() && std::isfinite(v[0]) && v[0] >= 0 && v[0] < 1e9f)
    sender = static_cast<std::uint64_t>(v[0]);
  if (auto st = algorithm_->receive_text(sender, bytes->text()); !st && !warned_malformed_) {
    log(os::LogLevel::kWarn, "medea: ignored a received genome (further ones are only counted): " + st.error());
    warned_malformed_ = true;
  }
  std::lock_guard lock(mu_);
  counts_ = algorithm_->counts();
}

namespace {

using os::ParamSpec;
using os::ParamType;

[[noreturn]] void fail_make(const std::string& what) { throw std::invalid_argument(what); }

std::size_t mlp_genome_size(const os::ParamSet& p) {
  auto n = evo::mlp_genome_size(p.integer("inputs"), p.string("layers"), p.string("activation"));
  if (!n) fail_make(n.error());
  return *n;
}

os::TaskType medea_type() {
  using namespace std::chrono_literals;
  os::TaskType t;
  t.name = "medea";
  t.doc =
      "mEDEA swarm evolution: broadcasts its genome over the `radio` task every period, runs one "
      "mlp per lifetime, the next picked among the genomes heard (docs/evolution.md)";
  const MedeaTaskOptions d;
  const MedeaOptions& a = d.algorithm;
  t.params = {
      {"lifetime", ParamType::kDuration, d.lifetime, 0.001, 86400.0, "how long each genome runs"},
      {"inputs", ParamType::kInt, std::int64_t{7}, 1.0, static_cast<double>(control::network::kMaxInputs),
       "the mlp's input count"},
      {"layers", ParamType::kString, std::string("2"), 1.0, 200.0, "the mlp's hidden then output sizes"},
      {"activation", ParamType::kString, std::string("tanh"), 1.0, 16.0, "the mlp's activation"},
      {"lo", ParamType::kReal, a.lo, -1e6, 1e6, "lowest gene value"},
      {"hi", ParamType::kReal, a.hi, -1e6, 1e6, "highest gene value"},
      {"sigma", ParamType::kReal, a.sigma, 1e-12, 1e6, "initial mutation step size (sigma_ref)"},
      {"sigma_min", ParamType::kReal, a.sigma_min, 1e-12, 1e6, "lowest step size"},
      {"sigma_max", ParamType::kReal, a.sigma_max, 1e-12, 1e6, "highest step size"},
      {"sigma_probability", ParamType::kReal, a.sigma_probability, 0.0, 1.0,
       "probability of changing sigma (x1.35 or x0.65) before each mutation"},
      {"controller", ParamType::kString, d.controller, 1.0, 63.0, "the name of the controller task it replaces"},
      {"sensor", ParamType::kString, d.sensor, 1.0, 63.0, "the task hooked into each controller"},
      {"actuator", ParamType::kString, d.actuator, 1.0, 63.0, "the task each controller drives"},
      {"radio", ParamType::kString, d.radio, 1.0, 63.0, "the radio task it broadcasts and listens through"},
  };
  t.defaults.priority = 1;
  t.defaults.period = 300ms;
  t.defaults.queue_capacity = 64;
  t.make = [](const os::ParamSet& p) -> std::unique_ptr<os::Task> {
    MedeaTaskOptions o;
    o.lifetime = p.duration("lifetime");
    o.algorithm.genes = mlp_genome_size(p);
    o.algorithm.lo = p.real("lo");
    o.algorithm.hi = p.real("hi");
    o.algorithm.sigma = p.real("sigma");
    o.algorithm.sigma_min = p.real("sigma_min");
    o.algorithm.sigma_max = p.real("sigma_max");
    o.algorithm.sigma_probability = p.real("sigma_probability");
    o.controller_type = "mlp";
    o.controller_params = "inputs=" + std::to_string(p.integer("inputs")) + " layers=\"" + p.string("layers") +
                          "\" activation=" + p.string("activation");
    o.controller = p.string("controller");
    o.sensor = p.string("sensor");
    o.actuator = p.string("actuator");
    o.radio = p.string("radio");
    auto task = MedeaTask::create(std::move(o));
    if (!task) fail_make(task.error());
    return std::move(task).value();
  };
  return t;
}

}  // namespace

kernel::Status register_medea_task_types(os::TaskTypeRegistry& registry) { return registry.add(medea_type()); }

}  // namespace symb::evo
