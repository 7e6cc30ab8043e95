// KinematicsTask ("kinematics"): the swarm demo's stand-in for a robot body and its world. Every
// period it integrates differential-drive (unicycle) motion from the latest wheel speeds inside a
// square walled arena and sends the pose (PoseLayout). The walls stop the body; the task reports
// contact rather than bouncing, so a controller that ignores its sensor visibly gets stuck.
#pragma once

#include "symb/os/task.hpp"
#include "symb/os/task_type_registry.hpp"

namespace symb::apps::swarm {

struct KinematicsParams {
  double arena = 4.0;            // side of the square arena, m
  double radius = 0.05;          // body radius, m
  double wheel_base = 0.1;       // m
  double max_wheel_speed = 0.5;  // m/s
  kernel::Duration command_timeout = std::chrono::milliseconds(200);
};

class KinematicsTask final : public os::Task {
 public:
  // The body must fit the arena (the type's factory checks it).
  explicit KinematicsTask(const KinematicsParams& params);

  // The registry entry: parameters arena, radius, wheel_base, max_wheel_speed, command_timeout;
  // period 10 ms.
  static os::TaskType type();

 protected:
  void on_start() override;
  void on_message(const os::Message& message) override;
  void on_tick() override;

 private:
  void send_pose();
  void note_contact(bool contact, const char* wall);

  const KinematicsParams p_;

  double x_ = 0, y_ = 0, heading_ = 0;
  double left_ = 0, right_ = 0;  // commanded wheel speeds, m/s
  double speed_ = 0, turn_rate_ = 0;
  bool contact_ = false;
  bool stopped_by_timeout_ = true;
  kernel::Time last_step_{0};
  kernel::Time last_command_{0};
};

}  // namespace symb::apps::swarm
