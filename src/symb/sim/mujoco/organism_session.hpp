// OrganismSession: a 3D scenario (world: {kind: mujoco}) made real, in process: the MuJoCo world
// of the scenario's modules (their kinds and starts, the docked pairs latched before anything
// runs), the MujocoRunner stepping it at the control period, and one RobotSystem (node, task
// graph) per module whose device tasks sit on that module's devices, all on one executor; the
// scenario's events on top. The 3D counterpart of ScenarioSession: the same scenario machinery
// (parse_scenario, check_scenario, RobotSystem, ScenarioEvents), another world.
//
// Docking at the start: parse_scenario has placed every docked module so that its connector
// coincides with its partner's (and checked the pair against the latch tolerances); create()
// latches each pair in file order through the world, and a pair the world refuses is an error at
// its place in the file. The latches reach the modules' logs at the first tick, like any other.
//
// Hooks between modules (RobotSpec::remote_hooks) ride the organism bus (organism_bus.hpp), made
// when the scenario has `world.bus` with its bandwidth and latency and attached to the runner, so
// the docked modules form its segments; a hook the bus refuses is an error at its place in the
// file. The modules' shells (events) make and list remote hooks through it too.
//
// Lifetime: as ScenarioSession. create() builds everything but starts nothing; start() attaches
// the runner and the events; the destructor stops both, detaches and empties every node, then
// lets the runner and the world go.
//
//   auto sc = load_scenario("scenarios/organism_chain.yaml");
//   kernel::VirtualTimeExecutor ex;
//   auto session = mujoco::OrganismSession::create(*sc, ex);
//   (*session)->start();
//   ex.run_for(sc->duration);
//   auto pose = (*session)->runner().with_world([](MujocoWorld& w) { ... });
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "symb/kernel/executor.hpp"
#include "symb/kernel/result.hpp"
#include "symb/sim/mujoco/module_battery.hpp"
#include "symb/sim/mujoco/mujoco_runner.hpp"
#include "symb/sim/mujoco/mujoco_world.hpp"
#include "symb/sim/mujoco/organism_bus.hpp"
#include "symb/sim/robot_system.hpp"
#include "symb/sim/scenario.hpp"
#include "symb/sim/scenario_events.hpp"
#include "symb/sim/scenario_session.hpp"

namespace symb::sim::mujoco {

class OrganismSession {
 public:
  // Checks the scenario (a 3D one; check_scenario against the task types a module offers) before
  // building anything; an error names the file, line and column where it can.
  static kernel::Result<std::unique_ptr<OrganismSession>> create(const Scenario& scenario, kernel::Executor& executor,
                                                                 SessionOptions options = {});
  ~OrganismSession();
  OrganismSession(const OrganismSession&) = delete;
  OrganismSession& operator=(const OrganismSession&) = delete;

  void start();
  void stop();

  const Scenario& scenario() const { return scenario_; }
  std::uint64_t seed() const { return seed_; }
  // The world: read or change it through runner().with_world() once the runner has started.
  MujocoWorld& world() { return *world_; }
  MujocoRunner& runner() { return *runner_; }
  std::size_t robot_count() const { return robots_.size(); }
  // Module i's system (its index in the scenario and the world). Throws std::out_of_range.
  RobotSystem& robot(std::size_t i) { return *robots_.at(i); }
  // The module named `name`, or null.
  RobotSystem* find_robot(std::string_view name);
  // The first cycle of answers a module's node cut (os/message.hpp, kMaxHops), or empty.
  std::string cycle_error() const;
  // Why the runner stopped on its own (the world failed a step: MujocoRunner::error()), or empty.
  std::string error() const;
  // The scenario's events, or null when it has none.
  ScenarioEvents* events() { return events_.get(); }
  // The organism bus (world.bus in the scenario), or null.
  OrganismBus* bus() { return bus_.get(); }
  // The modules' batteries (world.battery in the scenario), or null.
  ModuleBatteries* batteries() { return batteries_.get(); }

 private:
  OrganismSession() = default;
  // Connects the hooks of module `from_robot` that reach other modules' tasks over the organism
  // bus (scenario().organism.bus). Called by create() for every module that has any, after every
  // module's tasks exist; the first hook the bus refuses is the error, at its place.
  kernel::Status wire_remote_hooks(std::size_t from_robot, const std::vector<RemoteHookSpec>& hooks);

  Scenario scenario_;
  std::uint64_t seed_ = 1;
  std::unique_ptr<MujocoWorld> world_;
  std::unique_ptr<MujocoRunner> runner_;
  std::vector<std::unique_ptr<RobotSystem>> robots_;  // emptied before runner_ and world_ go
  std::unique_ptr<OrganismBus> bus_;                  // goes after the runner stops, before robots_
  std::unique_ptr<ModuleBatteries> batteries_;        // outlives robots_ (their devices point at it)
  std::unique_ptr<ScenarioEvents> events_;            // stopped before robots_ go
};

}  // namespace symb::sim::mujoco
