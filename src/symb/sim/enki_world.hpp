// EnkiWorld: the World interface on the Enki 2D simulator (Debian libenki-dev), with Thymio2
// robots. It builds Enki objects from a WorldSpec and keeps Enki behind this file: nothing else
// in the framework includes an Enki header.
//
// Walls: the arena's four sides are Enki's own square walls (cheap: a bounds test per body, where
// side walls as objects would cost a polygon test against every body and every other wall in every
// step, and Enki does not skip static-static pairs). Enki reports no collision events for them,
// so contacts with the sides are read off the body's hull after each step (see touched_sides in
// the .cpp). Every inner wall is a static rectangular Enki object (infinite mass) whose contacts
// come through collisionEvent(): its segment's length plus its thickness long (the ends are
// capped, so walls meeting at a corner leave no gap), `thickness` wide, spec.wall_height high.
//
// Determinism, within one process too. Enki is deterministic for a given object order and random
// state, but (a) it keeps its objects in a std::set ordered by pointer value and iterates it for
// collisions, sensors and noise draws, and (b) its noise comes from process-wide generators:
// motor noise from Enki::random (Enki's own IR sensors would draw from the C library's rand(),
// but their readings go stale in Debian's Enki 1.6.99, so they are switched off and IrModel
// computes IR instead, with its own noise stream: see ir_model.hpp). So:
//  - every Enki object of a world is placed in one address range reserved when the world is made
//    (see Options::max_robots), bump-allocated, so addresses increase in creation order and two
//    worlds built alike iterate alike, whatever the heap looked like;
//  - before each step the world reseeds Enki's generator from its OWN RandomStream (seeded from
//    the constructor's seed), and every Enki call that touches them (construction of objects,
//    step) holds one process-wide mutex. That mutex is the one justified global of the framework:
//    it stands for the globals inside Enki. Several worlds in one process, on any threads, are
//    then each deterministic and independent of the others.
//
// Thread safety: one world is not thread-safe (World's rule); different worlds may be used from
// different threads at once.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/result.hpp"
#include "symb/sim/ir_model.hpp"
#include "symb/sim/world.hpp"

namespace symb::sim {

class EnkiWorld final : public World {
 public:
  struct Options {
    // Robots this world can ever hold: their address space is reserved (not committed) up front,
    // which is what makes object addresses grow in creation order. add_robot() beyond it throws.
    // About 5 KB of address space per robot; the constructor throws std::length_error when the
    // system refuses the reservation.
    std::size_t max_robots = 4096;
    // Physics substeps per step (Enki's physicsOversampling); 1 as in the reference benchmark.
    unsigned physics_oversampling = 1;
  };

  // Throws std::invalid_argument (naming the wall's location) when check_spec() fails or the
  // options are out of range.
  EnkiWorld(WorldSpec spec, std::uint64_t seed) : EnkiWorld(std::move(spec), seed, Options{}) {}
  EnkiWorld(WorldSpec spec, std::uint64_t seed, Options options);
  ~EnkiWorld() override;
  EnkiWorld(const EnkiWorld&) = delete;
  EnkiWorld& operator=(const EnkiWorld&) = delete;

  // What this backend needs of a spec: a finite, positive arena and wall height; walls with
  // finite coordinates and a positive, finite thickness. The error gives the wall's location.
  static kernel::Status check_spec(const WorldSpec& spec);

  const WorldSpec& spec() const override { return spec_; }
  // Throws std::invalid_argument when `start` is not finite or outside [0, width] x [0, height],
  // std::length_error beyond Options::max_robots.
  std::size_t add_robot(const std::string& name, RobotKind kind, const Pose& start) override;
  std::size_t robot_count() const override { return robots_.size(); }
  // Throws std::out_of_range for a bad index (as do set_wheels, ir and state).
  const std::string& robot_name(std::size_t robot) const override;

  // Throws std::invalid_argument unless 0 < dt <= 1 (Enki's own limit for a sane step).
  void step(double dt) override;
  double time() const override { return time_; }
  std::uint64_t steps() const override { return steps_; }

  // NaN is refused (std::invalid_argument): a command that means nothing must not move a robot.
  void set_wheels(std::size_t robot, double left, double right) override;
  // The 7 IR values after the last step (all 0 before the first), clamped into [0, kIrMax]:
  // Enki adds Gaussian noise that can dip a far reading below 0.
  IrReadings ir(std::size_t robot) const override;
  RobotState state(std::size_t robot) const override;

  // Static Enki objects built for walls: one per inner wall (the sides are Enki's square walls).
  std::size_t wall_objects() const { return wall_count_; }

 private:
  class Arena;
  class Thymio;
  struct Robot {
    std::string name;
    Thymio* body = nullptr;  // lives in arena_
    RobotState state;
    IrReadings ir{};  // after the last step (all 0 before the first)
  };

  const Robot& robot_at(std::size_t robot, const char* what) const;

  WorldSpec spec_;
  Options options_;
  kernel::RandomStream random_;
  kernel::RandomStream ir_noise_;
  std::unique_ptr<IrModel> ir_model_;
  std::vector<Pose> poses_;  // scratch for the IR model
  // Declared before enki_ so that it outlives it: the Enki world holds pointers into the arena.
  std::unique_ptr<Arena> arena_;
  struct EnkiState;
  std::unique_ptr<EnkiState> enki_;
  std::vector<Robot> robots_;
  std::size_t wall_count_ = 0;
  std::uint64_t steps_ = 0;
  double time_ = 0;
};

}  // namespace symb::sim
