#include "symb/control/schemas/schema_tasks.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <variant>

#include "symb/os/message.hpp"
#include "symb/os/node.hpp"
#include "symb/robot/thymio_ir.hpp"

namespace symb::control {

namespace {

using behaviour::Point;

std::optional<Pose2> read_pose(const os::Message& m) {
  if (m.payload.blob || m.port != kSchemaInputPort) return std::nullopt;
  const auto v = m.numbers();
  if (v.size() != 3 || !os::all_finite(v)) return std::nullopt;
  return Pose2{v[0], v[1], v[2]};
}

// A world-frame direction (dx, dy) seen from a robot with `heading`.
Vec2 to_robot(double dx, double dy, double heading) {
  const double c = std::cos(heading), s = std::sin(heading);
  return {c * dx + s * dy, -s * dx + c * dy};
}

Vec2 scaled_toward(double dx, double dy, double magnitude, double heading) {
  const double n = std::hypot(dx, dy);
  if (n <= 0 || magnitude == 0) return {};
  return to_robot(dx / n * magnitude, dy / n * magnitude, heading);
}

}  // namespace

// --- the schema base -------------------------------------------------------------------------------

void MotorSchema::on_start() {
  const auto info = node().info(id());
  every_input_ = !info || info->period.count() == 0;
}

void MotorSchema::on_message(const os::Message& m) {
  if (take(m) && every_input_) evaluate();
}

void MotorSchema::on_tick() { evaluate(); }

void MotorSchema::evaluate() {
  const auto v = compute();
  if (!v) return;
  const bool finite = std::isfinite(v->x) && std::isfinite(v->y);
  const Vec2 out = finite ? *v : Vec2{};
  const bool active = out.x != 0 || out.y != 0;
  vx_.store(out.x, std::memory_order_relaxed);
  vy_.store(out.y, std::memory_order_relaxed);
  active_.store(active, std::memory_order_relaxed);
  evaluations_.fetch_add(1, std::memory_order_relaxed);
  const float x = static_cast<float>(out.x), y = static_cast<float>(out.y);
  send(kSchemaVectorPort, {x, y});
  probe("vector", {x, y});
  probe("active", {active ? 1.0f : 0.0f});
}

// --- avoid obstacle --------------------------------------------------------------------------------

Vec2 AvoidObstacleSchema::vector_for(std::span<const float> ir, const AvoidObstacleOptions& o) {
  Vec2 sum;
  double largest = 0;
  Vec2 largest_dir;
  const std::size_t n = std::min(ir.size(), robot::thymio::kIrCount);
  for (std::size_t i = 0; i < n; ++i) {
    const double d = robot::thymio::ir_distance(ir[i]);
    double m = 0;
    if (d <= o.safety) {
      m = o.gain * o.near_gain;
    } else if (d <= o.sphere && d < robot::thymio::kIrRange) {
      m = o.gain * (o.sphere - d) / (o.sphere - o.safety);
    }
    if (m <= 0) continue;
    // The obstacle sits d in front of its sensor; push away from it, seen from the robot's centre.
    const auto& mount = robot::thymio::kIrMounts[i];
    const double px = mount.x + d * std::cos(mount.angle), py = mount.y + d * std::sin(mount.angle);
    const double len = std::hypot(px, py);
    const Vec2 away{-px / len, -py / len};
    sum.x += m * away.x;
    sum.y += m * away.y;
    if (m > largest) {
      largest = m;
      largest_dir = away;
    }
  }
  if (!o.use_max || largest == 0) return sum;
  // Balch: the magnitude of the strongest obstacle, in the direction of all of them together
  // (the strongest one's direction when they cancel out).
  const double n2 = std::hypot(sum.x, sum.y);
  const Vec2 dir = n2 > 1e-9 * largest ? Vec2{sum.x / n2, sum.y / n2} : largest_dir;
  return {largest * dir.x, largest * dir.y};
}

bool AvoidObstacleSchema::take(const os::Message& m) {
  if (m.payload.blob || m.port != kSchemaInputPort) return false;
  const auto v = m.numbers();
  if (v.size() != robot::thymio::kIrCount || !os::all_finite(v)) return false;
  ir_.assign(v.begin(), v.end());
  return true;
}

std::optional<Vec2> AvoidObstacleSchema::compute() {
  if (ir_.empty()) return std::nullopt;
  return vector_for(ir_, o_);
}

kernel::Status AvoidObstacleSchema::on_parameter_changed(std::string_view name) {
  if (name == "gain") set_gain(o_.gain);
  if ((name == "sphere" || name == "safety") && !(o_.safety < o_.sphere))
    return kernel::Error{"safety (R) must be less than sphere (S)"};
  return {};
}

// --- move to goal ----------------------------------------------------------------------------------

bool MoveToGoalSchema::take(const os::Message& m) {
  auto p = read_pose(m);
  if (!p) return false;
  pose_ = p;
  return true;
}

std::optional<Vec2> MoveToGoalSchema::compute() {
  if (!pose_) return std::nullopt;
  const Pose2 p = *pose_;
  std::size_t k = target_.load(std::memory_order_relaxed);
  while (k < o_.via.size() && std::hypot(o_.via[k].x - p.x, o_.via[k].y - p.y) <= o_.reach) ++k;
  target_.store(k, std::memory_order_relaxed);
  const Point t = k < o_.via.size() ? o_.via[k] : o_.goal;
  const double dx = t.x - p.x, dy = t.y - p.y;
  if (k >= o_.via.size() && std::hypot(dx, dy) <= o_.arrive) return Vec2{};
  return scaled_toward(dx, dy, o_.gain, p.heading);
}

kernel::Status MoveToGoalSchema::on_parameter_changed(std::string_view name) {
  if (name == "gain") set_gain(o_.gain);
  if (name == "via") target_.store(0, std::memory_order_relaxed);
  return {};
}

// --- stay on path ----------------------------------------------------------------------------------

namespace {

// The point of segment ab nearest to p.
Point nearest_on_segment(Point a, Point b, Point p) {
  const double ex = b.x - a.x, ey = b.y - a.y;
  const double len2 = ex * ex + ey * ey;
  double t = len2 > 0 ? ((p.x - a.x) * ex + (p.y - a.y) * ey) / len2 : 0;
  t = std::clamp(t, 0.0, 1.0);
  return {a.x + t * ex, a.y + t * ey};
}

double distance(Point a, Point b) { return std::hypot(a.x - b.x, a.y - b.y); }

}  // namespace

bool StayOnPathSchema::take(const os::Message& m) {
  auto p = read_pose(m);
  if (!p) return false;
  pose_ = p;
  return true;
}

std::optional<Vec2> StayOnPathSchema::compute() {
  if (!pose_ || o_.path.size() < 2) return std::nullopt;
  const Point p{pose_->x, pose_->y};
  const std::size_t segments = o_.path.size() - 1;
  const auto near = [&](std::size_t s) { return nearest_on_segment(o_.path[s], o_.path[s + 1], p); };
  if (!segment_) {
    // First pose: the nearest segment of all.
    std::size_t best = 0;
    for (std::size_t s = 1; s < segments; ++s)
      if (distance(near(s), p) < distance(near(best), p)) best = s;
    segment_ = best;
  }
  // Progress only forward, one segment at a time: in a serpentine the segment beyond a wall may
  // be as near as the robot's own.
  if (*segment_ + 1 < segments && distance(near(*segment_ + 1), p) <= distance(near(*segment_), p)) ++*segment_;
  const Point q = near(*segment_);
  const double d = distance(q, p);
  const double half = o_.width / 2;
  const double m = d > half ? gain() : gain() * d / half;
  return scaled_toward(q.x - p.x, q.y - p.y, m, pose_->heading);
}

kernel::Status StayOnPathSchema::on_parameter_changed(std::string_view name) {
  if (name == "gain") set_gain(o_.gain);
  if (name == "path") segment_.reset();
  return {};
}

// --- noise -----------------------------------------------------------------------------------------

bool NoiseSchema::take(const os::Message& /*m*/) { return false; }

std::optional<Vec2> NoiseSchema::compute() {
  const kernel::Time t = now();
  if (!next_ || t >= *next_) {
    angle_ = random().uniform(-std::numbers::pi, std::numbers::pi);
    next_ = t + o_.persistence;
  }
  return Vec2{gain() * std::cos(angle_), gain() * std::sin(angle_)};
}

kernel::Status NoiseSchema::on_parameter_changed(std::string_view name) {
  if (name == "gain") set_gain(o_.gain);
  if (name == "persistence") next_.reset();
  return {};
}

// --- the sum ---------------------------------------------------------------------------------------

std::pair<float, float> SchemaSum::wheels_for(Vec2 v, const SchemaSumOptions& o) {
  const double mag = std::hypot(v.x, v.y);
  if (!std::isfinite(mag) || mag < o.min_magnitude) return {0.0f, 0.0f};
  const double a = std::atan2(v.y, v.x);
  const double forward = o.speed * std::min(mag, 1.0) * std::max(std::cos(a), 0.0);
  const double turn = o.turn_speed * std::clamp(a / (std::numbers::pi / 2), -1.0, 1.0);
  const auto limit = [&](double w) { return static_cast<float>(std::clamp(w, -o.speed_limit, o.speed_limit)); };
  return {limit(forward - turn), limit(forward + turn)};
}

void SchemaSum::on_message(const os::Message& m) {
  if (m.payload.blob || m.port != kSchemaVectorPort) return;
  const auto v = m.numbers();
  if (v.size() != 2 || !os::all_finite(v)) return;
  for (auto& e : entries_)
    if (e.source == m.source) {
      e.v = {v[0], v[1]};
      e.time = m.time;
      return;
    }
  if (entries_.size() >= kMaxSchemas) return;
  entries_.push_back({m.source, {v[0], v[1]}, m.time});
}

void SchemaSum::on_tick() {
  const kernel::Time t = now();
  // A schema that went silent (removed, suspended, starved of input) stops counting.
  std::erase_if(entries_, [&](const Entry& e) { return t - e.time > o_.max_age; });
  Vec2 sum;
  for (const auto& e : entries_) {
    sum.x += e.v.x;
    sum.y += e.v.y;
  }
  const auto [left, right] = wheels_for(sum, o_);
  ticks_.fetch_add(1, std::memory_order_relaxed);
  send(kSumWheelPort, {left, right});
  probe("sum", {static_cast<float>(sum.x), static_cast<float>(sum.y)});
  probe("wheels", {left, right});
}

}  // namespace symb::control
