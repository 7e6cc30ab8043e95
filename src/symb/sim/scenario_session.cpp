#include "symb/sim/scenario_session.hpp"

#include <exception>
#include <limits>

#include "symb/io/plugin_library.hpp"
#include "symb/sim/world_factory.hpp"

namespace symb::sim {

kernel::Result<std::unique_ptr<ScenarioSession>> ScenarioSession::create(const Scenario& scenario,
                                                                         kernel::Executor& executor,
                                                                         SessionOptions options) {
  if (scenario.world_kind != WorldKind::kEnki)
    return kernel::Error{scenario.file + ": this scenario describes a 3D world: an OrganismSession runs it"};
  std::unique_ptr<ScenarioSession> s(new ScenarioSession());
  s->scenario_ = scenario;
  s->seed_ = options.seed.value_or(scenario.seed);
  ProgramReader read = options.read_program ? options.read_program : file_program_reader(scenario.base_dir);
  // The scenario's plugins, after those the caller gives: types beyond the built-in ones.
  std::vector<RegisterTaskTypes> extra_types = options.task_types;
  for (const PluginRef& p : scenario.plugins) {
    auto lib = io::PluginLibrary::open(p.path);
    if (!lib) return kernel::Error{p.where.str() + ": " + lib.error()};
    extra_types.push_back([lib = std::move(lib).value()](os::TaskTypeRegistry& r) { return lib->register_into(r); });
  }
  const auto add_extra_types = [&extra_types](os::TaskTypeRegistry& r) -> kernel::Status {
    for (const RegisterTaskTypes& add : extra_types)
      if (auto st = add(r); !st) return st;
    return {};
  };

  {
    os::TaskTypeRegistry schemas;
    if (auto st = register_scenario_task_types(schemas, {}, read); !st) return kernel::Error{st.error()};
    if (auto st = add_extra_types(schemas); !st) return kernel::Error{scenario.file + ": " + st.error()};
    if (auto st = check_scenario(scenario, schemas); !st) return kernel::Error{st.error()};
  }
  if (scenario.robots.empty()) return kernel::Error{scenario.file + ": the scenario has no robots"};
  try {
    s->world_ = make_world(scenario.world, s->seed_, scenario.robots.size());
    for (const RobotSpec& r : scenario.robots) s->world_->add_robot(r.name, r.kind, r.start);
    WorldRunner::Options ro;
    ro.period = scenario.control_period;
    // Above any priority a task can have (a scenario and the shell give at most 1000): at an
    // instant it shares with a robot's tasks the world moves first, on the main lane of a lockstep
    // executor as on a single virtual-time one, so both give the same run.
    ro.priority = std::numeric_limits<int>::max();
    s->world_->set_parallel(executor.parallel());
    s->runner_ = std::make_unique<WorldRunner>(executor, *s->world_, ro);
  } catch (const std::exception& e) {
    return kernel::Error{scenario.file + ": " + e.what()};
  }
  if (const auto& spec = scenario.world.radio) {
    auto radio = LocalRadio::create(scenario.robots.size(), {spec->range, spec->max_message_bytes});
    if (!radio) return kernel::Error{scenario.file + ": radio: " + radio.error()};
    s->radio_ = std::move(radio).value();
    s->radio_->attach(*s->runner_);
  }
  // One copy of the types that hold nothing of one robot, for every robot (robot_system.hpp).
  auto shared_types = shared_scenario_task_types(read, add_extra_types);
  if (!shared_types) return kernel::Error{scenario.file + ": " + shared_types.error()};
  for (std::size_t i = 0; i < scenario.robots.size(); ++i) {
    RobotSystemOptions ro;
    ro.shared_types = shared_types.value();
    ro.control_period = scenario.control_period;
    ro.seed = robot_node_seed(s->seed_, i);
    ro.log_capacity = options.log_capacity;
    ro.read_program = read;
    auto built =
        RobotSystem::build(executor.lane(i), scenario.robots[i],
                           RobotDevices{s->runner_->ir_sensor(i), s->runner_->wheels(i), s->runner_->pose_sensor(i),
                                        s->runner_->ground_sensor(i), s->radio_.get(), i, std::nullopt},
                           std::move(ro));
    if (!built) return kernel::Error{built.error()};
    s->robots_.push_back(std::move(built).value());
  }
  if (!scenario.events.empty()) {
    std::vector<ScenarioEvents::Robot> targets;
    for (std::size_t i = 0; i < s->robots_.size(); ++i)
      targets.push_back({&s->robots_[i]->node(), world_runner_devices(*s->runner_, i), {}});
    s->events_ = std::make_unique<ScenarioEvents>(executor, scenario.events, std::move(targets));
  }
  return s;
}

ScenarioSession::~ScenarioSession() {
  events_.reset();
  if (runner_) runner_->stop();
  robots_.clear();  // every node emptied (RobotSystem's destructor) before the drivers' runner goes
}

void ScenarioSession::start() {
  if (runner_ && !runner_->running()) (void)runner_->start();
  if (events_) (void)events_->start();
}

void ScenarioSession::stop() {
  if (events_) events_->stop();
  if (runner_) runner_->stop();
}

std::string ScenarioSession::cycle_error() const { return first_cycle_error(robots_); }

RobotSystem* ScenarioSession::find_robot(std::string_view name) { return sim::find_robot(robots_, name); }

}  // namespace symb::sim
