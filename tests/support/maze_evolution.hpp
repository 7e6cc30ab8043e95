// Shared by the maze evolution tests (one_plus_one, mu_plus_one): the maze demo's scenarios with
// the controller removed or replaced, a fitness task on a node, and a replay that measures a
// controller with that fitness.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "symb/evo/fitness/fitness_task.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/sim/scenario_session.hpp"

#include "support/shipped_scenario.hpp"

namespace symb::sim::maze_test {

using test::load_shipped;

// The maze with no controller: only the device tasks.
inline Scenario bare_maze() {
  Scenario s = load_shipped("maze.yaml");
  for (RobotSpec& r : s.robots) {
    r.tasks.clear();
    r.hooks.clear();
  }
  return s;
}

// The maze with a 7-2 tanh perceptron whose weights are `weights` (numbers or a file reference).
inline Scenario maze_with_perceptron(const std::string& weights) {
  Scenario s = load_shipped("braitenberg.yaml");  // maze.yaml's world, the mlp controller
  for (RobotSpec& r : s.robots)
    for (TaskSpec& t : r.tasks)
      for (os::ParamAssignment& p : t.params)
        if (p.name == "weights") p.value = weights;
  return s;
}

// Adds a fitness task hooked from `ir` (and from the controller when there is one), reporting
// after every `every`-th step.
inline evo::FitnessTask* add_fitness(os::Node& node, std::uint32_t every = 1) {
  evo::FitnessTaskOptions o;
  o.every = every;
  auto f = std::make_unique<evo::FitnessTask>(o);
  evo::FitnessTask* p = f.get();
  const auto id = node.create("fitness", std::move(f), {.priority = 1, .queue_capacity = 8});
  EXPECT_TRUE(id.ok());
  EXPECT_TRUE(node.hook(*node.find("ir"), *id).ok());
  if (auto c = node.find("controller")) {
    EXPECT_TRUE(node.hook(*c, *id).ok());
  }
  return p;
}

struct Replay {
  double fitness = 0;  // mean per-step
  std::uint64_t contact_steps = 0;
  double distance = 0;
};

// Runs `scenario` for `duration` with a fitness task added to its first robot.
inline Replay replay(const Scenario& scenario, kernel::Duration duration) {
  kernel::VirtualTimeExecutor executor;
  auto session = ScenarioSession::create(scenario, executor);
  EXPECT_TRUE(session.ok()) << (session ? "" : session.error());
  if (!session) return {};
  evo::FitnessTask* fitness = add_fitness((*session)->robot(0).node());
  (*session)->start();
  executor.run_for(duration);
  (*session)->stop();
  const RobotState s = (*session)->world().state(0);
  return {fitness->mean(), s.contact_steps, s.distance};
}

}  // namespace symb::sim::maze_test
