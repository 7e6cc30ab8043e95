// Shared by the simulation benchmarks: the baseline that does what `symb run` does minus the
// framework. A 2D world (the scenario's engine, built by sim::make_world) stepped in a loop, and one
// MDL2e interpreter per robot running the maze demo's program, called directly: no node, task,
// hook, message or executor. The interpreter is stepped as the mdl2e task steps it under the
// type's default priorities (mdl2e_task.hpp): at each period's instant the sensor task's new
// vector comes first, so the controller's tick finds it waiting and steps once, on the new vector;
// the next world step uses that command. Same scenario, same seed: the robots end where `symb
// run`'s end, bit for bit (bench_sim_rtf checks it).
#pragma once

#include <time.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "symb/control/mdl2e/compiler.hpp"
#include "symb/control/mdl2e/interpreter.hpp"
#include "symb/sim/scenario.hpp"
#include "symb/sim/sim_drivers.hpp"
#include "symb/sim/world.hpp"
#include "symb/sim/world_factory.hpp"

namespace symb::bench {

// CPU time of the running thread: on a shared box wall time counts other processes' turns
// against whichever side they interrupted.
inline double thread_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// The maze demo's controller (scenarios/mdl2e/obstacle_avoidance.mdl2e), compiled once per process
// as the mdl2e task type does per robot.
inline std::shared_ptr<const control::mdl2e::Program> maze_program() {
  static const std::shared_ptr<const control::mdl2e::Program> program = [] {
    std::ifstream in(std::filesystem::path(SYMB_SCENARIO_DIR) / "mdl2e" / "obstacle_avoidance.mdl2e");
    std::ostringstream text;
    text << in.rdbuf();
    auto compiled = control::mdl2e::compile_source(text.str());
    if (!compiled) throw std::runtime_error("obstacle_avoidance.mdl2e: " + compiled.error());
    return std::make_shared<const control::mdl2e::Program>(std::move(compiled).value());
  }();
  return program;
}

// The scenario in `file`, parsed as `symb run` parses it, once per process and file.
inline const sim::Scenario& parsed_scenario(const std::filesystem::path& file) {
  static std::map<std::string, sim::Scenario> cache;
  auto it = cache.find(file.string());
  if (it != cache.end()) return it->second;
  auto sc = sim::load_scenario(file.string());
  if (!sc) throw std::runtime_error(sc.error());
  return cache.emplace(file.string(), std::move(sc).value()).first->second;
}

class RawWorldMdl2e {
 public:
  static constexpr double kDt = 0.03;

  // The world and starts of `sc` (its engine unless `engine` says otherwise).
  explicit RawWorldMdl2e(const sim::Scenario& sc) : RawWorldMdl2e(sc, sc.world.engine) {}
  RawWorldMdl2e(const sim::Scenario& sc, sim::Engine2d engine) : program_(maze_program()) {
    sim::WorldSpec spec = sc.world;
    spec.engine = engine;
    world_ = sim::make_world(spec, sc.seed, std::max<std::size_t>(sc.robots.size(), 1));
    for (const sim::RobotSpec& r : sc.robots) world_->add_robot(r.name, r.kind, r.start);
    robots_.reserve(sc.robots.size());
    for (std::size_t i = 0; i < sc.robots.size(); ++i)
      robots_.push_back(Robot{control::mdl2e::Interpreter(*program_), {}, {}});
  }

  void step() {
    for (std::size_t i = 0; i < robots_.size(); ++i) world_->set_wheels(i, robots_[i].wheels[0], robots_[i].wheels[1]);
    world_->step(kDt);
    ++steps_;
    const kernel::Time now{std::chrono::microseconds(30'000 * steps_)};
    for (std::size_t i = 0; i < robots_.size(); ++i) {
      Robot& r = robots_[i];
      const sim::IrReadings ir = world_->ir(i);
      for (std::size_t k = 0; k < sim::kIrCount; ++k)
        r.sensors[k] = std::clamp(ir[k], 0.0f, static_cast<float>(sim::kIrMax));
      command(r, now);
    }
  }

  sim::Pose pose(std::size_t robot) const { return world_->state(robot).pose; }

  // Sum of the positions, so the compiler cannot drop the work.
  double checksum() const {
    double s = 0;
    for (std::size_t i = 0; i < robots_.size(); ++i) s += pose(i).x + pose(i).y;
    return s;
  }

 private:
  struct Robot {
    control::mdl2e::Interpreter interpreter;
    std::array<double, sim::kIrCount> sensors;
    std::array<double, 2> wheels;  // cm/s, for the next world step
  };

  // A wheel speed as the controller task sends it: finite, within +-500 units, as a float.
  static float wheel_units(double v) {
    if (!std::isfinite(v)) return 0.0f;
    return static_cast<float>(std::clamp(v, -double{sim::kWheelUnitsMax}, double{sim::kWheelUnitsMax}));
  }
  // One interpreter step and its command as the wheels apply it, in cm/s.
  static void command(Robot& r, kernel::Time now) {
    const control::mdl2e::Output out = r.interpreter.step(now, {r.sensors, 0});
    const float left = out.running ? wheel_units(out.left) : 0.0f;
    const float right = out.running ? wheel_units(out.right) : 0.0f;
    r.wheels = {sim::wheel_units_to_cm_per_s(left), sim::wheel_units_to_cm_per_s(right)};
  }

  std::shared_ptr<const control::mdl2e::Program> program_;
  std::unique_ptr<sim::World> world_;
  std::vector<Robot> robots_;
  std::int64_t steps_ = 0;
};

}  // namespace symb::bench
