// ScenarioSession: a scenario made real, in-process: the Enki world with the scenario's walls and
// robots, the world runner stepping it at the control period, the simulated drivers, and one
// RobotSystem (node, task graph) per robot. Robot i's node runs on executor.lane(i) (its own lane
// under a kernel::LockstepExecutor, the executor itself otherwise); the world runner, the radio
// and the events run on the executor itself, and the world gets executor.parallel(). Robots meet
// only through the world and the radio, which is what lets a lockstep executor run their lanes
// in parallel between world steps. It is what `symb run` runs and
// what tests drive step by step; recording and output files are the caller's business (observe
// the runner).
//
// Lifetime: create() builds everything but starts nothing; start() attaches the runner and the
// scenario's events (the robots' tasks already run: they wait for sensor data); the destructor stops the runner and
// empties every node before the world goes away, so no task touches a freed driver.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "symb/kernel/executor.hpp"
#include "symb/kernel/result.hpp"
#include "symb/sim/local_radio.hpp"
#include "symb/sim/robot_system.hpp"
#include "symb/sim/scenario.hpp"
#include "symb/sim/scenario_events.hpp"
#include "symb/sim/world.hpp"
#include "symb/sim/world_runner.hpp"

namespace symb::sim {

// Adds task types to a registry (a plugin's, io/plugin_library.hpp; Python's; a test's).
using RegisterTaskTypes = std::function<kernel::Status(os::TaskTypeRegistry&)>;

struct SessionOptions {
  std::optional<std::uint64_t> seed;  // overrides the scenario's
  ProgramReader read_program;         // default: files relative to the scenario's folder
  std::size_t log_capacity = 1024;
  // Task types beyond the built-in ones (`symb run --plugin`), added, like the plugins the
  // scenario names (Scenario::plugins, loaded by create()), to the registry the scenario is
  // checked against and to the types every robot shares. 2D scenarios only.
  std::vector<RegisterTaskTypes> task_types;
};

class ScenarioSession {
 public:
  // Checks the scenario against the task types (check_scenario) before building anything.
  static kernel::Result<std::unique_ptr<ScenarioSession>> create(const Scenario& scenario, kernel::Executor& executor,
                                                                 SessionOptions options = {});
  ~ScenarioSession();
  ScenarioSession(const ScenarioSession&) = delete;
  ScenarioSession& operator=(const ScenarioSession&) = delete;

  void start();
  void stop();

  const Scenario& scenario() const { return scenario_; }
  std::uint64_t seed() const { return seed_; }
  World& world() { return *world_; }
  WorldRunner& runner() { return *runner_; }
  std::size_t robot_count() const { return robots_.size(); }
  RobotSystem& robot(std::size_t i) { return *robots_.at(i); }
  // The robot named `name`, or null.
  RobotSystem* find_robot(std::string_view name);
  // The first cycle of answers a robot's node cut (os/message.hpp, kMaxHops), empty when there was
  // none: a command running the session stops on it and fails with it.
  std::string cycle_error() const;
  // The world's radio medium (world.radio in the scenario), or null.
  LocalRadio* radio() { return radio_.get(); }
  // The scenario's events (scenario.events), or null when it has none.
  ScenarioEvents* events() { return events_.get(); }

 private:
  ScenarioSession() = default;
  Scenario scenario_;
  std::uint64_t seed_ = 1;
  std::unique_ptr<World> world_;
  std::unique_ptr<LocalRadio> radio_;  // observes runner_: destroyed after it
  std::unique_ptr<WorldRunner> runner_;
  std::vector<std::unique_ptr<RobotSystem>> robots_;  // destroyed before runner_ and world_
  std::unique_ptr<ScenarioEvents> events_;            // stopped before robots_ go
};

}  // namespace symb::sim
