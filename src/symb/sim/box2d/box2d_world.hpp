// Box2DWorld: the World interface on Box2D 2.4 (Debian libbox2d-dev), for swarms of thousands.
// EnkiWorld tests every pair of objects in every step; Box2D finds contacts through a dynamic
// AABB tree, so a step costs about the same per robot at 10,000 robots as at 100. It behaves like
// EnkiWorld: the same Thymio2 footprint (Enki's hull: an 8 cm front arc and a flat back 3 cm
// behind the axle, 11 cm wide), axle (9.4 cm), speed limit and motor noise (each wheel's speed
// times a factor uniform in [1 - 0.027, 1 + 0.027]); the same walls (each inner wall a static box
// of its segment's length plus its thickness by its thickness, and the four arena sides); the
// same contacts, distances, IR model and bad-input contract. Box2D stays behind this file.
//
// Motion: before each step every robot's velocity is set from its wheels, as Enki's
// DifferentialWheeled does (forward speed along the heading at mid-step, turn rate from the wheel
// difference over the axle, the wheel speeds set before the PREVIOUS step: Enki's one step of
// actuation delay); Box2D then resolves the contacts. Nothing keeps momentum from one step to the
// next: a robot a neighbour pushed stops when the push ends, as in Enki. Contacts do not turn a
// robot (its wheels' grip does not let them); only its wheels do.
//
// Determinism: nothing of a run depends on anything outside its world, so worlds built alike
// step alike, on any thread. Box2D does keep process-wide state (a table it fills on first use,
// statistics counters every collision query bumps); none of it feeds back into a result, but
// worlds on different threads would race on it, so every Box2D call of every world holds one
// process-wide mutex (it stands for those globals, as EnkiWorld's does for Enki's). Each robot
// draws its motor noise and its IR noise from its own streams (seeded from the world's seed and
// the robot's index), so the IR readings of different robots are independent jobs: with
// set_parallel() they run on several threads, outside that mutex, and give the same bits as one.
//
// Thread safety: one world is not thread-safe (World's rule); different worlds may be used from
// different threads at once.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/result.hpp"
#include "symb/sim/world.hpp"

namespace symb::sim {

class Box2DWorld final : public World {
 public:
  // Throws std::invalid_argument when check_spec() fails.
  Box2DWorld(WorldSpec spec, std::uint64_t seed);
  ~Box2DWorld() override;
  Box2DWorld(const Box2DWorld&) = delete;
  Box2DWorld& operator=(const Box2DWorld&) = delete;

  // The same rules as EnkiWorld::check_spec (a finite, positive arena and wall height; walls
  // with finite coordinates and a positive, finite thickness), with the wall's location.
  static kernel::Status check_spec(const WorldSpec& spec);

  const WorldSpec& spec() const override { return spec_; }
  // Throws std::invalid_argument when `start` is not finite or outside [0, width] x [0, height],
  // std::length_error beyond kMaxBodies robots.
  std::size_t add_robot(const std::string& name, RobotKind kind, const Pose& start) override;
  std::size_t robot_count() const override { return robots_.size(); }
  // Throws std::out_of_range for a bad index (as do set_wheels, ir and state).
  const std::string& robot_name(std::size_t robot) const override;

  // Throws std::invalid_argument unless 0 < dt <= 1 (and, after begin_next_step, unless dt is
  // the begun step's).
  void step(double dt) override;
  bool can_step_ahead() const override { return true; }
  void begin_next_step(double dt) override;
  double time() const override { return time_; }
  std::uint64_t steps() const override { return steps_; }

  // NaN is refused (std::invalid_argument); speeds are clamped to +-kMaxWheelSpeed.
  void set_wheels(std::size_t robot, double left, double right) override;
  // The 7 IR values after the last step (all 0 before the first), in [0, kIrMax].
  IrReadings ir(std::size_t robot) const override;
  RobotState state(std::size_t robot) const override;

  // IR readings after each step run through `parallel` (null: on the caller's thread).
  void set_parallel(kernel::ParallelFor* parallel) override { parallel_ = parallel; }

  // Robots one world holds at most: far beyond a scenario's kMaxRobots, a bound on a world's
  // memory for callers that build worlds themselves.
  static constexpr std::size_t kMaxBodies = 1 << 20;

 private:
  struct Robot {
    std::string name;
    RobotState state;
    // The wheel speeds this step moves with: those set before the previous step. Enki moves a
    // robot with the speed its wheels gave it at the end of the previous step, so a command acts
    // one step later than set; a reactive controller in a maze turns measurably later for it.
    double acting_left = 0, acting_right = 0;
    IrReadings ir{};             // after the last step (all 0 before the first)
    kernel::RandomStream motor;  // wheel noise
    kernel::RandomStream ir_noise;
  };
  struct Engine;  // Box2D's world and bodies

  const Robot& robot_at(std::size_t robot, const char* what) const;
  // The wheels' velocities from the acting speeds, which then become those set since, and
  // Box2D's step: the physics of a step, which begin_next_step may run early.
  void advance(double dt);
  void settle();  // poses, distances and contacts after advance()
  void read_ir();

  WorldSpec spec_;
  std::uint64_t seed_;
  std::unique_ptr<Engine> engine_;
  std::vector<Robot> robots_;
  std::vector<Pose> poses_;  // every robot's pose after the last step, for the IR model
  kernel::ParallelFor* parallel_ = nullptr;
  std::uint64_t steps_ = 0;
  double time_ = 0;
  double begun_dt_ = 0;  // > 0: advance(begun_dt_) ran for the next step (begin_next_step)
};

}  // namespace symb::sim
