#include "symb/sim/mujoco/organism_session.hpp"

#include <algorithm>
#include <exception>

#include "symb/shell/command_line.hpp"

namespace symb::sim::mujoco {

namespace {

// The optional device tasks (connector_<name>) module `robot` needs beyond its own hooks: the
// ends of other modules' remote hooks on it, and those its events name as tasks (an `ioctl` names
// the device, which needs no task).
std::vector<std::string> organism_named_tasks(const Scenario& sc, std::size_t robot) {
  std::vector<std::string> names;
  for (const RobotSpec& r : sc.robots)
    for (const RemoteHookSpec& h : r.remote_hooks)
      if (h.to_index == robot && is_device_task_name(h.to)) names.push_back(h.to);
  for (const EventSpec& e : sc.events) {
    if (e.robot != robot) continue;
    auto tokens = shell::tokenize(e.line);
    if (!tokens || tokens->empty()) continue;
    const std::string& command = tokens->front().text;
    if (command == "ioctl" || command == "ioctls" || command == "devices") continue;
    for (const shell::Token& t : *tokens)
      if (t.text.rfind(kConnectorTaskPrefix, 0) == 0) names.push_back(t.text);
  }
  return names;
}

// Latches world.docked's pairs in file order; an error at the pair the world refuses.
kernel::Status latch_docked(const Scenario& scenario, MujocoWorld& world) {
  for (const DockSpec& d : scenario.organism.docked) {
    const std::string pair =
        scenario.robots[d.a].name + "." + d.connector_a + " and " + scenario.robots[d.b].name + "." + d.connector_b;
    const auto ca = world.find_connector(d.a, d.connector_a);
    const auto cb = world.find_connector(d.b, d.connector_b);
    if (!ca || !cb) return kernel::Error{d.where.str() + ": " + pair + ": no such connector in the world"};
    if (auto st = world.latch(d.a, *ca); !st)
      return kernel::Error{d.where.str() + ": " + pair + " cannot latch: " + st.error()};
    const auto to = world.docked_to(d.a, *ca);
    if (!to || *to != std::pair<std::size_t, std::size_t>{d.b, *cb}) {
      (void)world.unlatch(d.a, *ca);
      return kernel::Error{d.where.str() + ": " + pair + " cannot latch: " + scenario.robots[d.a].name + "." +
                           d.connector_a + " latched to another connector, nearer to it"};
    }
  }
  return {};
}

}  // namespace

kernel::Result<std::unique_ptr<OrganismSession>> OrganismSession::create(const Scenario& scenario,
                                                                         kernel::Executor& executor,
                                                                         SessionOptions options) {
  if (scenario.world_kind != WorldKind::kMujoco)
    return kernel::Error{scenario.file + ": this scenario describes a 2D world: a ScenarioSession runs it"};
  if (scenario.robots.empty()) return kernel::Error{scenario.file + ": the scenario has no robots"};
  std::unique_ptr<OrganismSession> s(new OrganismSession());
  s->scenario_ = scenario;
  s->seed_ = options.seed.value_or(scenario.seed);
  ProgramReader read = options.read_program ? options.read_program : file_program_reader(scenario.base_dir);
  {
    os::TaskTypeRegistry schemas;
    RobotDevices checking;
    checking.module = robot::RobotDevices{};
    if (auto st = register_scenario_task_types(schemas, checking, read); !st) return kernel::Error{st.error()};
    if (auto st = check_scenario(scenario, schemas); !st) return kernel::Error{st.error()};
  }

  std::vector<ModuleSpec> modules;
  std::size_t connectors = 0;
  for (const RobotSpec& r : scenario.robots) {
    modules.push_back({r.name, r.module_kind, r.module_start});
    connectors += r.module_kind.connectors.size();
  }
  ModelOptions model;
  // Enough welds for every connector to be docked at once: a dock takes two connectors.
  model.spare_welds = std::max<std::size_t>(1, connectors / 2);
  auto made = MujocoWorld::make(std::move(modules), model);
  if (!made) return kernel::Error{scenario.file + ": " + made.error()};
  s->world_ = std::make_unique<MujocoWorld>(std::move(made).value());
  try {
    PeriodicRunner::Options ro;
    ro.period = scenario.control_period;
    s->runner_ = std::make_unique<MujocoRunner>(executor, *s->world_, ro);
  } catch (const std::exception& e) {
    return kernel::Error{scenario.file + ": " + e.what()};
  }

  if (const auto& spec = scenario.organism.battery) {
    BatteryModel battery;
    battery.capacity = spec->capacity;
    auto made_batteries = ModuleBatteries::create(*s->runner_, battery);
    if (!made_batteries) return kernel::Error{spec->where.str() + ": " + made_batteries.error()};
    s->batteries_ = std::move(made_batteries).value();
    for (std::size_t i = 0; i < scenario.robots.size(); ++i) s->batteries_->set_sharing(i, spec->share);
  }
  for (std::size_t i = 0; i < scenario.robots.size(); ++i) {
    RobotSystemOptions ro;
    ro.control_period = scenario.control_period;
    ro.seed = robot_node_seed(s->seed_, i);
    ro.log_capacity = options.log_capacity;
    ro.read_program = read;
    ro.named_device_tasks = organism_named_tasks(scenario, i);
    RobotDevices devices;
    devices.module = s->runner_->device_lookups(i);
    if (s->batteries_) {
      // The battery is one more sensor of the module, by name, for `sensor device=battery`.
      devices.module->sensor = [battery = s->batteries_->device(i), others = devices.module->sensor](
                                   std::string_view name) -> std::shared_ptr<robot::Sensor> {
        if (name == battery->name()) return battery;
        return others ? others(name) : nullptr;
      };
    }
    auto built = RobotSystem::build(executor, scenario.robots[i], std::move(devices), std::move(ro));
    if (!built) return kernel::Error{built.error()};
    s->robots_.push_back(std::move(built).value());
    s->runner_->set_node(i, &s->robots_.back()->node());
  }
  // Latched once the runner watches the world's docking log, so the modules' logs hear of them.
  kernel::Status docked;
  s->runner_->with_world([&](MujocoWorld& world) { docked = latch_docked(scenario, world); });
  if (!docked) return kernel::Error{docked.error()};
  if (const auto& spec = scenario.organism.bus) {
    std::vector<os::Node*> nodes;
    for (auto& r : s->robots_) nodes.push_back(&r->node());
    OrganismBusOptions bo;
    bo.bandwidth = static_cast<double>(spec->bandwidth);
    bo.latency = spec->latency;
    auto bus = OrganismBus::create(executor, std::move(nodes), bo);
    if (!bus) return kernel::Error{spec->where.str() + ": " + bus.error()};
    s->bus_ = std::move(bus).value();
    s->bus_->attach(*s->runner_);
  }
  for (std::size_t i = 0; i < scenario.robots.size(); ++i)
    if (!scenario.robots[i].remote_hooks.empty())
      if (auto st = s->wire_remote_hooks(i, scenario.robots[i].remote_hooks); !st) return kernel::Error{st.error()};

  if (!scenario.events.empty()) {
    std::vector<ScenarioEvents::Robot> targets;
    for (std::size_t i = 0; i < s->robots_.size(); ++i) {
      auto table = std::make_shared<shell::DeviceTable>();
      for (const auto& d : s->runner_->devices(i)) (*table)[d->name()] = d;
      if (s->batteries_) (*table)[s->batteries_->device(i)->name()] = s->batteries_->device(i);
      ScenarioEvents::Robot target{&s->robots_[i]->node(), std::move(table), {}};
      if (OrganismBus* bus = s->bus_.get()) target.serve = [bus](shell::Shell::Options& o) { bus->serve_shell(o); };
      targets.push_back(std::move(target));
    }
    s->events_ = std::make_unique<ScenarioEvents>(executor, scenario.events, std::move(targets));
  }
  return s;
}

kernel::Status OrganismSession::wire_remote_hooks(std::size_t from_robot, const std::vector<RemoteHookSpec>& hooks) {
  for (const RemoteHookSpec& h : hooks) {
    if (!bus_) return kernel::Error{h.where.str() + ": a hook between modules needs world.bus"};  // parse checks it
    auto made = bus_->hook(from_robot, h.from, h.to_index, h.to, h.options);
    if (!made) return kernel::Error{h.where.str() + ": " + made.error()};
  }
  return {};
}

OrganismSession::~OrganismSession() {
  events_.reset();
  if (runner_) {
    runner_->stop();
    for (std::size_t i = 0; i < robots_.size(); ++i) runner_->set_node(i, nullptr);
  }
  // The runner no longer ticks, so its observer (the bus's) is never called again; the bus takes
  // its proxies off the nodes, which must still be there.
  bus_.reset();
  robots_.clear();     // every node emptied (RobotSystem's destructor) before the devices' runner goes
  batteries_.reset();  // the runner no longer ticks: its observer (the batteries') is not called again
  runner_.reset();
  world_.reset();
}

void OrganismSession::start() {
  if (runner_ && !runner_->running()) (void)runner_->start();
  if (events_) (void)events_->start();
}

void OrganismSession::stop() {
  if (events_) events_->stop();
  if (runner_) runner_->stop();
}

RobotSystem* OrganismSession::find_robot(std::string_view name) { return sim::find_robot(robots_, name); }

std::string OrganismSession::cycle_error() const { return first_cycle_error(robots_); }

std::string OrganismSession::error() const { return runner_ ? runner_->error() : std::string(); }

}  // namespace symb::sim::mujoco
