// ScenarioEvents: a scenario's `events` (EventSpec) carried out: at each event's time after the
// run's start, its shell line runs through a shell::Shell on its robot's node, with the robot's
// devices in the shell's device table, exactly as a user's line would. The reply (the command's
// output, or its error) goes to that node's log, at error level for a failure; a failing event
// never stops the run. Used by both sessions (2D ScenarioSession, 3D OrganismSession).
//
// It is one activity of the robots' executor that sleeps until the next event is due (its period
// is reset to the gap each time), so it costs nothing between events and a scenario without
// events has none. At one instant it runs before the world runner and every task (priority
// kEventPriority), so a latch commanded at t holds for the world step at t. Events of one time
// run in file order.
//
// Lifetime: the nodes must outlive it; the destructor stops it and waits until the executor has
// let go of it (like PeriodicRunner: destroy it outside the executor's handlers).
#pragma once

#include <condition_variable>
#include <cstddef>
#include <functional>
#include <memory>
#include <mutex>
#include <vector>

#include "symb/kernel/executor.hpp"
#include "symb/kernel/result.hpp"
#include "symb/shell/shell.hpp"
#include "symb/sim/scenario.hpp"

namespace symb::os {
class Node;
}

namespace symb::sim {

inline constexpr int kEventPriority = 200;  // above the world runners (100) and every task
inline constexpr std::string_view kEventLogSource = "event";

class ScenarioEvents final : private kernel::Activity {
 public:
  // The robot an event acts on: its node and the devices its shell may name (may be null).
  struct Robot {
    os::Node* node = nullptr;
    std::shared_ptr<const shell::DeviceTable> devices;
    // Adds what else the robot's shell offers (the organism bus's remote hooks); may be empty.
    std::function<void(shell::Shell::Options&)> serve;
  };
  // `robots` in the scenario's order (EventSpec::robot indexes it). Throws std::out_of_range for
  // an event whose robot is not in `robots`.
  ScenarioEvents(kernel::Executor& executor, std::vector<EventSpec> events, std::vector<Robot> robots);
  ~ScenarioEvents() override;
  ScenarioEvents(const ScenarioEvents&) = delete;
  ScenarioEvents& operator=(const ScenarioEvents&) = delete;

  // Attaches the activity: event times count from now. Fails when already started.
  kernel::Status start();
  // Detaches it; the events not yet due never run.
  void stop();
  // Events carried out so far, and how many of them failed. Any thread.
  std::size_t done() const;
  std::size_t failed() const;

 private:
  void on_activity_attached(kernel::ActivitySlot& slot) override;
  void on_activity_start() override;
  void on_activity_input() override {}
  void on_activity_tick() override;
  void on_activity_stop() override {}
  void on_activity_released() override;
  // Runs every event due by now, then sleeps until the next one (or detaches when none is left).
  void run_due();

  kernel::Executor& executor_;
  std::vector<EventSpec> events_;  // sorted by time, ties in file order
  std::vector<Robot> robots_;
  std::vector<std::unique_ptr<shell::Shell>> shells_;  // per robot, made at its first event
  kernel::Time start_{0};
  std::size_t next_ = 0;  // the first event not yet run; only the activity's handlers touch it

  mutable std::mutex mu_;  // slot_, attached_, done_, failed_
  std::condition_variable released_cv_;
  kernel::ActivitySlot* slot_ = nullptr;
  bool attached_ = false;
  std::size_t done_ = 0;
  std::size_t failed_ = 0;
};

// The devices of 2D robot `robot` of a world runner, by device name, for an event's shell.
class WorldRunner;
std::shared_ptr<const shell::DeviceTable> world_runner_devices(const WorldRunner& runner, std::size_t robot);

}  // namespace symb::sim
