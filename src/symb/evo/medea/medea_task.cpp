#include "symb/evo/medea/medea_task.hpp"

#include <cmath>
#include <utility>
#include <vector>

#include "symb/control/network/network.hpp"
#include "symb/evo/controller_swap.hpp"
#include "symb/evo/genome/genome.hpp"
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

// The medea type's parameters: the task's options and the mlp's shape.
struct MedeaParams : MedeaTaskOptions {
  std::int64_t inputs = 7;
  std::string layers = "2";
  std::string activation = "tanh";
};

os::TaskType medea_type() {
  using namespace std::chrono_literals;
  using P = MedeaParams;
  using A = MedeaOptions;
  os::ParamTable<P> p;
  p.add("lifetime", &P::lifetime).range(0.001, 86400.0).doc("how long each genome runs");
  p.add("inputs", &P::inputs)
      .range(1.0, static_cast<double>(control::network::kMaxInputs))
      .doc("the mlp's input count");
  p.add("layers", &P::layers).range(1.0, 200.0).doc("the mlp's hidden then output sizes");
  p.add("activation", &P::activation).range(1.0, 16.0).doc("the mlp's activation");
  p.add("lo", &P::algorithm, &A::lo).range(-1e6, 1e6).doc("lowest gene value");
  p.add("hi", &P::algorithm, &A::hi).range(-1e6, 1e6).doc("highest gene value");
  p.add("sigma", &P::algorithm, &A::sigma).range(1e-12, 1e6).doc("initial mutation step size (sigma_ref)");
  p.add("sigma_min", &P::algorithm, &A::sigma_min).range(1e-12, 1e6).doc("lowest step size");
  p.add("sigma_max", &P::algorithm, &A::sigma_max).range(1e-12, 1e6).doc("highest step size");
  p.add("sigma_probability", &P::algorithm, &A::sigma_probability)
      .range(0.0, 1.0)
      .doc("probability of changing sigma (x1.35 or x0.65) before each mutation");
  p.add("controller", &P::controller).range(1.0, 63.0).doc("the name of the controller task it replaces");
  p.add("sensor", &P::sensor).range(1.0, 63.0).doc("the task hooked into each controller");
  p.add("actuator", &P::actuator).range(1.0, 63.0).doc("the task each controller drives");
  p.add("radio", &P::radio).range(1.0, 63.0).doc("the radio task it broadcasts and listens through");
  auto t =
      os::declare_task_type("medea",
                            "mEDEA swarm evolution: broadcasts its genome over the `radio` task every period, runs one "
                            "mlp per lifetime, the next picked among the genomes heard (docs/evolution.md)",
                            std::move(p), [](const P& c) -> kernel::Result<std::unique_ptr<MedeaTask>> {
                              auto genes = mlp_genome_size(c.inputs, c.layers, c.activation);
                              if (!genes) return kernel::Error{genes.error()};
                              MedeaTaskOptions o = c;
                              o.algorithm.genes = *genes;
                              o.controller_type = "mlp";
                              o.controller_params = mlp_params_text(c.inputs, c.layers, c.activation);
                              return MedeaTask::create(std::move(o));
                            });
  t.defaults.priority = 1;
  t.defaults.period = 300ms;
  t.defaults.queue_capacity = 64;
  return t;
}

}  // namespace

kernel::Status register_medea_task_types(os::TaskTypeRegistry& registry) { return registry.add(medea_type()); }

}  // namespace symb::evo
