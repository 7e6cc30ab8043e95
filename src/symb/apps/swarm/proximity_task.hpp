// ProximityTask ("proximity"): a polled range sensor with four rays fixed to the robot body
// (front, left, back, right). It keeps the latest pose it was sent (from "kinematics") and, every
// period, sends the free distance along each ray to the arena's walls (ProximityLayout), capped at
// its range and blurred by Gaussian noise from its own random stream. It is the simulated driver
// a real IR ring would replace.
#pragma once

#include "symb/os/task.hpp"
#include "symb/os/task_type_registry.hpp"

namespace symb::apps::swarm {

struct ProximityParams {
  double arena = 4.0;    // side of the square arena, m
  double range = 0.5;    // farthest distance sensed, m
  double noise = 0.005;  // standard deviation of the reading, m
};

class ProximityTask final : public os::Task {
 public:
  explicit ProximityTask(const ProximityParams& params) : p_(params) { bind_parameters(p_); }

  // The registry entry: parameters arena, range, noise; period 30 ms (the paper's 33 Hz IR).
  static os::TaskType type();

 protected:
  void on_message(const os::Message& message) override;
  void on_tick() override;

 private:
  double ray(double angle) const;

  ProximityParams p_;  // range and noise change at runtime
  bool have_pose_ = false;
  double x_ = 0, y_ = 0, heading_ = 0;
};

}  // namespace symb::apps::swarm
