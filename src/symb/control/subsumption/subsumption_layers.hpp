// Subsumption layers (Brooks 1986; paper section III-A): each layer of competence is a task that
// sends [left, right] wheel commands on port 0 while it is active and stays silent otherwise. The
// arbitration is not in the layers but in the hooks into the wheels (docs/subsumption.md):
//  - suppression: a layer's hook into the wheels has a higher hook priority and a suppress window;
//    each of its commands blocks lower-priority hooks into the wheels for that window, so a silent
//    higher layer lets the lower ones through again once its window has passed;
//  - inhibition: a layer may name another task (`inhibit`) whose output it blocks, through all of
//    that task's hooks, for `inhibit_for` after each of its own active steps (Node::inhibit).
// Layers can be created, removed and replaced at runtime (subsumption_rewiring.hpp): the paper's
// "dynamic subsumption".
//
// Every layer probes ("active", {0|1}) and ("output", {left, right}) at each step.
#pragma once

#include <atomic>
#include <cstdint>
#include <optional>
#include <string>

#include "symb/kernel/time.hpp"
#include "symb/os/ids.hpp"
#include "symb/os/task.hpp"

namespace symb::control {

inline constexpr os::Port kLayerInputPort = 0;
inline constexpr os::Port kLayerOutputPort = 0;

struct LayerOptions {
  std::string inhibit;              // a task whose output this layer blocks while active; empty: none
  kernel::Duration inhibit_for{0};  // how long each active step blocks it
  double speed_limit = 500;         // commands are clamped to +-this (Thymio motor units)
};

// What every layer shares: sending a command (clamped, never NaN), inhibiting, probing.
class SubsumptionLayer : public os::Task {
 public:
  explicit SubsumptionLayer(LayerOptions options) : options_(std::move(options)) { bind_parameters(options_); }
  // Safe from any thread.
  bool active() const { return active_.load(std::memory_order_relaxed); }
  std::uint64_t commands() const { return commands_.load(std::memory_order_relaxed); }

 protected:
  // Sends [left, right] as this layer's output and marks the step active.
  void act(double left, double right);
  // Marks the step inactive (nothing is sent).
  void rest();

 private:
  LayerOptions options_;
  std::atomic<bool> active_{false};
  std::atomic<std::uint64_t> commands_{0};
};

// The lowest layer: forward with random turns. Every tick (its period) it sends
// [speed - turn, speed + turn]; `turn` is redrawn uniformly in [-turn_max, turn_max] from the task's
// random stream after a time drawn uniformly in [change_every / 2, 3 change_every / 2]. Always
// active. Needs a period.
struct WanderOptions {
  double speed = 200;
  double turn_max = 100;
  kernel::Duration change_every = std::chrono::seconds(2);
};
class WanderLayer : public SubsumptionLayer {
 public:
  WanderLayer(WanderOptions options, LayerOptions layer) : SubsumptionLayer(std::move(layer)), o_(options) {
    bind_parameters(o_);
  }

 protected:
  void on_tick() override;
  kernel::Status on_parameter_changed(std::string_view name) override;

 private:
  WanderOptions o_;
  double turn_ = 0;
  std::optional<kernel::Time> next_change_;
};

// Obstacle avoidance: IR vectors (7 values) in on port 0. Active while any front sensor (0..4)
// reads above `threshold`, and for `hold` after the last such reading (an AFSM timer). While
// active it sends [forward + turn, forward - turn] turning away from the side that sees more
// (weights: far 2, near 1; the centre alone keeps the previous direction, or turns right); the
// direction chosen at the start of an episode is kept until it ends, so it does not dither in a
// corner. Silent otherwise. Malformed vectors are ignored.
struct AvoidOptions {
  double threshold = 1500;  // about 12 cm from the sensor
  double turn = 200;
  double forward = 0;
  kernel::Duration hold{0};
};
class AvoidLayer : public SubsumptionLayer {
 public:
  AvoidLayer(AvoidOptions options, LayerOptions layer) : SubsumptionLayer(std::move(layer)), o_(options) {
    bind_parameters(o_);
  }

 protected:
  void on_message(const os::Message& m) override;

 private:
  AvoidOptions o_;
  bool episode_ = false;
  double direction_ = -1;  // +1 turn left (counter-clockwise), -1 right
  kernel::Time last_seen_{0};
};

// Stops in a target zone: ground readings [left, right] (floor reflectance 0..1) in on port 0.
// Active while both readings lie in [zone_min, zone_max] and have done so for at least `after`
// (so the lower layers carry the robot that much further in: the ground sensors sit at its front
// edge); then sends [0, 0] at each reading. With `latch`, once active it stays active for good.
// Malformed readings are ignored.
struct StopInZoneOptions {
  double zone_min = 0;
  double zone_max = 0.5;
  bool latch = false;
  kernel::Duration after{0};
};
class StopInZoneLayer : public SubsumptionLayer {
 public:
  StopInZoneLayer(StopInZoneOptions options, LayerOptions layer) : SubsumptionLayer(std::move(layer)), o_(options) {
    bind_parameters(o_);
  }

 protected:
  void on_message(const os::Message& m) override;
  kernel::Status on_parameter_changed(std::string_view name) override;

 private:
  StopInZoneOptions o_;
  bool latched_ = false;
  std::optional<kernel::Time> entered_;  // since when both readings are in the zone
};

}  // namespace symb::control
