// World: the simulator seen from the framework. A world holds robots, steps its physics by a
// fixed dt, gives each robot's sensor readings and takes its wheel speeds. Backends implement it
// (EnkiWorld); the world runner, the simulated device drivers and the hardware-in-the-loop link
// use only this interface, so a second backend slots in without touching them.
//
// Robots are named by index (a handle): the order in which they were added, never a pointer.
// Thread safety: none here; the world runner serialises access (see world_runner.hpp).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

#include "symb/kernel/parallel_for.hpp"
#include "symb/robot/thymio_ir.hpp"
#include "symb/sim/world_spec.hpp"

namespace symb::kernel {
class ParallelFor;
}

namespace symb::sim {

// Thymio2's 7 horizontal IR proximity sensors: 0 far left, 1 left, 2 centre, 3 right, 4 far
// right (front), 5 back left, 6 back right. Raw response, 0 (nothing in range) to about 4505.
inline constexpr std::size_t kIrCount = robot::thymio::kIrCount;
inline constexpr double kIrMax = robot::thymio::kIrMax;
// Thymio2's wheel speed limit in Enki, cm/s.
inline constexpr double kMaxWheelSpeed = 16.6;

using IrReadings = std::array<float, kIrCount>;

struct RobotState {
  Pose pose;
  double left_speed = 0;            // cm/s, as last set
  double right_speed = 0;           // cm/s
  std::uint64_t contact_steps = 0;  // steps during which the robot touched a wall or a robot
  bool in_contact = false;          // during the last step
  double distance = 0;              // cm travelled (sum of |displacement| per step)
};

class World {
 public:
  virtual ~World() = default;

  virtual const WorldSpec& spec() const = 0;
  // Adds a robot at `start`; returns its index. Throws std::invalid_argument on a pose outside
  // the arena (scenarios are validated before they reach a world).
  virtual std::size_t add_robot(const std::string& name, RobotKind kind, const Pose& start) = 0;
  virtual std::size_t robot_count() const = 0;
  virtual const std::string& robot_name(std::size_t robot) const = 0;

  // Advances physics by dt seconds; afterwards ir() and state() describe the new instant.
  virtual void step(double dt) = 0;
  virtual double time() const = 0;  // seconds simulated so far
  virtual std::uint64_t steps() const = 0;

  // Wheel speeds in cm/s, clamped to +-kMaxWheelSpeed; they act from the next step on.
  virtual void set_wheels(std::size_t robot, double left, double right) = 0;
  virtual IrReadings ir(std::size_t robot) const = 0;
  virtual RobotState state(std::size_t robot) const = 0;

  // Stepping ahead. A world whose step moves each robot with the wheel speeds set before the
  // previous step (Enki's one-step actuation delay) knows a whole period early how its next step
  // will move the bodies. begin_next_step(dt), called right after step(dt), does that part (the
  // physics) at once; the next step(dt) then only makes it visible (poses, contacts, IR). Between
  // the two, ir(), state() and set_wheels() behave as if nothing had begun, so a runner may move
  // the physics onto another thread while the robots think (kernel::Executor::
  // run_alongside_lanes) and get the same run, bit for bit. Default: cannot; begin is a no-op.
  virtual bool can_step_ahead() const { return false; }
  virtual void begin_next_step(double /*dt*/) {}

  // Threads for the per-robot work of a step (IR sensing), or null for the caller's thread. A
  // backend that uses them gives the same results, bit for bit, as without. The object must
  // outlive the world or be unset first. Default: ignored (everything on the caller's thread).
  virtual void set_parallel(kernel::ParallelFor* /*parallel*/) {}
};

}  // namespace symb::sim
