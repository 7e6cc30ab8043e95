// TrailTask: the swarm demo's observer, hooked to a robot's "kinematics" output: it writes every
// pose it is sent into a TrajectoryLog that the application owns and reads once the node is gone.
// It is a harness probe, not part of the robot, so it is made in code rather than registered as a
// task type: a registry factory receives parameters only, and a log is not a parameter.
#pragma once

#include "symb/apps/swarm/trajectory_log.hpp"
#include "symb/os/task.hpp"

namespace symb::apps::swarm {

class TrailTask final : public os::Task {
 public:
  // `log` must outlive the task. Under a concurrent executor only this task's thread writes it;
  // read it after the node has been destroyed (which joins every handler).
  explicit TrailTask(TrajectoryLog& log) : log_(log) {}

 protected:
  void on_message(const os::Message& message) override;

 private:
  TrajectoryLog& log_;
};

}  // namespace symb::apps::swarm
