// Motor schemas (Arkin 1989, Balch; paper section III-B and Fig. 5): each schema is a task hooked
// to the sensors it needs; it decides whether it is active and produces a vector. A summing task
// hooked to all of them adds the vectors up at its own fixed rate and turns the sum into wheel
// speeds. Schemas run at their own rates: one with a period evaluates at its ticks (from its
// newest input), one without evaluates at every good input message.
//
// Vectors: [vx, vy] on port 0, in the robot frame (x forward, y to the left, cm-free: a magnitude
// of 1 asks for the summing task's full speed). Each schema's gain (Arkin's G) is its own
// parameter; an inactive schema sends [0, 0], so the sum drops it at once.
//
//   avoid_obstacle  IR (7 values) -> away from each obstacle seen; per obstacle at distance d from
//                   its sensor: 0 for d > S, G (S - d) / (S - R) for R < d <= S, G * near_gain for
//                   d <= R (Arkin's infinity); combined by `sum`, or by `max` (Balch's Clay
//                   v_Avoid_va: the summed direction with the largest single magnitude, so a wall
//                   seen by several sensors does not count several times).
//   move_to_goal    pose [x, y, heading] -> G toward the current target: the `via` waypoints in
//                   turn (each passed when within `reach`), then the goal; 0 within `arrive` of it.
//   stay_on_path    pose -> toward the nearest point of the path polyline: G outside the path's
//                   width, G * d / (width / 2) inside it (d: distance to the centre line).
//   noise           (its period) -> G in a random direction, redrawn every `persistence`.
//   schema_sum      vectors -> [left, right] (docs/motor_schemas.md).
//
// Probes: schemas ("vector", {vx, vy}) and ("active", {0|1}) at each evaluation; the summing task
// ("sum", {vx, vy}) and ("wheels", {left, right}) at each tick.
#pragma once

#include <atomic>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "symb/control/schemas/waypoints.hpp"
#include "symb/kernel/time.hpp"
#include "symb/os/ids.hpp"
#include "symb/os/task.hpp"

namespace symb::control {

inline constexpr os::Port kSchemaInputPort = 0;
inline constexpr os::Port kSchemaVectorPort = 0;
inline constexpr os::Port kSumWheelPort = 0;

struct Vec2 {
  double x = 0, y = 0;
};

// What every schema shares: when to evaluate, sending and probing the vector.
class MotorSchema : public os::Task {
 public:
  explicit MotorSchema(double gain) : gain_(gain) {}
  // The last vector sent (thread-safe copies for tests and the shell).
  Vec2 vector() const { return {vx_.load(std::memory_order_relaxed), vy_.load(std::memory_order_relaxed)}; }
  bool active() const { return active_.load(std::memory_order_relaxed); }
  std::uint64_t evaluations() const { return evaluations_.load(std::memory_order_relaxed); }

 protected:
  void on_start() override;
  void on_message(const os::Message& m) override;
  void on_tick() override;

  // Takes an input message; false when it is not one this schema reads (ignored).
  virtual bool take(const os::Message& m) = 0;
  // The schema's vector, or nothing when it has no input yet (nothing is sent then).
  virtual std::optional<Vec2> compute() = 0;
  double gain() const { return gain_; }
  // A schema whose options' gain changed at runtime passes it on.
  void set_gain(double g) { gain_ = g; }

 private:
  void evaluate();
  double gain_;
  bool every_input_ = true;
  std::atomic<double> vx_{0}, vy_{0};
  std::atomic<bool> active_{false};
  std::atomic<std::uint64_t> evaluations_{0};
};

struct AvoidObstacleOptions {
  double gain = 1;
  double sphere = 12;  // S, cm from the sensor (the IR sees up to 14)
  double safety = 1;   // R, cm
  double near_gain = 5;
  bool use_max = true;  // combine=max (Balch) or sum (Arkin)
};
class AvoidObstacleSchema : public MotorSchema {
 public:
  explicit AvoidObstacleSchema(AvoidObstacleOptions o) : MotorSchema(o.gain), o_(o) { bind_parameters(o_); }
  // The vector for one IR vector (7 readings), without a task: for tests and other controllers.
  static Vec2 vector_for(std::span<const float> ir, const AvoidObstacleOptions& o);

 protected:
  bool take(const os::Message& m) override;
  std::optional<Vec2> compute() override;
  kernel::Status on_parameter_changed(std::string_view name) override;

 private:
  AvoidObstacleOptions o_;
  std::vector<float> ir_;
};

// A pose: [x cm, y cm, heading rad], as the `pose` device task sends it.
struct Pose2 {
  double x = 0, y = 0, heading = 0;
};

struct MoveToGoalOptions {
  double gain = 1;
  behaviour::Point goal;
  std::vector<behaviour::Point> via;
  double reach = 12;  // cm: a via waypoint counts as passed within this
  double arrive = 3;  // cm: at the goal the schema rests
};
class MoveToGoalSchema : public MotorSchema {
 public:
  explicit MoveToGoalSchema(MoveToGoalOptions o) : MotorSchema(o.gain), o_(std::move(o)) { bind_parameters(o_); }
  std::size_t target_index() const { return target_.load(std::memory_order_relaxed); }

 protected:
  bool take(const os::Message& m) override;
  std::optional<Vec2> compute() override;
  kernel::Status on_parameter_changed(std::string_view name) override;

 private:
  MoveToGoalOptions o_;
  std::optional<Pose2> pose_;
  std::atomic<std::size_t> target_{0};
};

struct StayOnPathOptions {
  double gain = 1;
  std::vector<behaviour::Point> path;  // at least 2 points
  double width = 20;                   // cm
};
class StayOnPathSchema : public MotorSchema {
 public:
  explicit StayOnPathSchema(StayOnPathOptions o) : MotorSchema(o.gain), o_(std::move(o)) { bind_parameters(o_); }

 protected:
  bool take(const os::Message& m) override;
  std::optional<Vec2> compute() override;
  kernel::Status on_parameter_changed(std::string_view name) override;

 private:
  StayOnPathOptions o_;
  std::optional<Pose2> pose_;
  std::optional<std::size_t> segment_;  // progress along the path: only this segment and the next count
};

struct NoiseOptions {
  double gain = 0.2;
  kernel::Duration persistence = std::chrono::seconds(1);
};
class NoiseSchema : public MotorSchema {
 public:
  explicit NoiseSchema(NoiseOptions o) : MotorSchema(o.gain), o_(o) { bind_parameters(o_); }

 protected:
  bool take(const os::Message& m) override;
  std::optional<Vec2> compute() override;
  kernel::Status on_parameter_changed(std::string_view name) override;

 private:
  NoiseOptions o_;
  double angle_ = 0;
  std::optional<kernel::Time> next_;
};

// The summing task: keeps each sender's newest vector (by message source, at most
// kMaxSchemas senders), and at every tick sums those younger than `max_age` and sends
// [left, right]: with a the sum's angle and |v| its magnitude,
//   forward = speed * min(|v|, 1) * max(cos a, 0),  turn = turn_speed * clamp(a / (pi/2), -1, 1),
//   left = forward - turn, right = forward + turn  (clamped to +-speed_limit; [0, 0] below
//   min_magnitude). So it turns toward the vector's direction, on the spot when it points behind.
struct SchemaSumOptions {
  double speed = 300;
  double turn_speed = 150;
  kernel::Duration max_age = std::chrono::milliseconds(500);
  double min_magnitude = 0.05;
  double speed_limit = 500;
};
class SchemaSum : public os::Task {
 public:
  static constexpr std::size_t kMaxSchemas = 32;
  explicit SchemaSum(SchemaSumOptions o) : o_(o) { bind_parameters(o_); }
  // The wheel speeds for a summed vector.
  static std::pair<float, float> wheels_for(Vec2 sum, const SchemaSumOptions& o);
  std::uint64_t ticks() const { return ticks_.load(std::memory_order_relaxed); }

 protected:
  void on_message(const os::Message& m) override;
  void on_tick() override;

 private:
  struct Entry {
    os::TaskId source;
    Vec2 v;
    kernel::Time time;
  };
  SchemaSumOptions o_;
  std::vector<Entry> entries_;
  std::atomic<std::uint64_t> ticks_{0};
};

}  // namespace symb::control
