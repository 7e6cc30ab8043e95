#include "symb/sim/ir_model.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <utility>

#include "symb/robot/thymio_ir.hpp"

namespace symb::sim {

namespace {

namespace thymio = robot::thymio;
using thymio::kIrMounts;
constexpr double kM = thymio::kIrMax, kNoiseSd = 2.87;
constexpr double kAperture = 15.0 * M_PI / 180.0;
constexpr double kMountReach = 8.0;  // cm: no sensor sits farther from the centre (7.95 at most)

// Per sensor, the cosine and sine of its three rays' angles on the robot: left, centre, right.
using RayDirections = std::array<std::array<std::pair<double, double>, 3>, kIrCount>;
const RayDirections& ray_directions() {
  static const RayDirections dirs = [] {
    RayDirections d{};
    for (std::size_t i = 0; i < kIrCount; ++i)
      for (int k = 0; k < 3; ++k) {
        const double a = kIrMounts[i].angle + (1 - k) * kAperture;
        d[i][static_cast<std::size_t>(k)] = {std::cos(a), std::sin(a)};
      }
    return d;
  }();
  return dirs;
}

// Enki's response of one ray (and 0 beyond IrModel::kRange, which is the sensor's range).
double response(double x) { return thymio::ir_reading(x); }

// Distance along the ray (px, py) + t (ux, uy), t in [0, limit], to segment s; `limit` if none.
double hit_segment(double px, double py, double ux, double uy, double ax, double ay, double bx, double by,
                   double limit) {
  const double ex = bx - ax, ey = by - ay;
  const double denom = ux * ey - uy * ex;
  if (std::fabs(denom) < 1e-12) return limit;
  const double wx = ax - px, wy = ay - py;
  const double t = (wx * ey - wy * ex) / denom;
  const double s = (wx * uy - wy * ux) / denom;
  if (t < 0 || t > limit || s < 0 || s > 1) return limit;
  return t;
}

}  // namespace

IrModel::IrModel(std::vector<Rect> walls) {
  walls_.reserve(walls.size());
  for (const Rect& r : walls) {
    const double c = std::cos(r.angle), s = std::sin(r.angle);
    const double lx = c * r.half_length, ly = s * r.half_length;  // along
    const double wx = -s * r.half_width, wy = c * r.half_width;   // across
    const double xs[4] = {r.cx + lx + wx, r.cx - lx + wx, r.cx - lx - wx, r.cx + lx - wx};
    const double ys[4] = {r.cy + ly + wy, r.cy - ly + wy, r.cy - ly - wy, r.cy + ly - wy};
    Wall w{r.cx, r.cy, std::hypot(r.half_length, r.half_width), {}};
    for (int i = 0; i < 4; ++i) w.edges[i] = {xs[i], ys[i], xs[(i + 1) % 4], ys[(i + 1) % 4]};
    walls_.push_back(w);
  }
}

double IrModel::ray(double px, double py, double ux, double uy) const {
  double best = kRange + 1;  // beyond range: no response
  for (const Segment& e : near_edges_) best = std::min(best, hit_segment(px, py, ux, uy, e.x1, e.y1, e.x2, e.y2, best));
  for (const Pose& robot : near_robots_) {
    const double dx = robot.x - px, dy = robot.y - py;
    const double along = dx * ux + dy * uy;
    const double across2 = dx * dx + dy * dy - along * along;
    const double r2 = kRobotRadius * kRobotRadius;
    if (across2 > r2) continue;
    const double t = along - std::sqrt(r2 - across2);
    if (t >= 0 && t < best)
      best = t;
    else if (t < 0 && along + std::sqrt(r2 - across2) >= 0)
      best = 0;  // the sensor is inside it
  }
  return best;
}

IrReadings IrModel::read(std::size_t self, std::span<const Pose> robots, kernel::RandomStream& noise) const {
  const Pose& p = robots[self];
  // Anything a ray can hit lies within kRange + 1 of a sensor, and every sensor within
  // kMountReach of the robot's centre.
  near_edges_.clear();
  for (const Wall& w : walls_) {
    const double reach = w.reach + kRange + 1 + kMountReach;
    const double dx = w.cx - p.x, dy = w.cy - p.y;
    if (dx * dx + dy * dy <= reach * reach)
      near_edges_.insert(near_edges_.end(), std::begin(w.edges), std::end(w.edges));
  }
  near_robots_.clear();
  const double robot_reach = kRobotRadius + kRange + 1 + kMountReach;
  for (std::size_t j = 0; j < robots.size(); ++j) {
    const double dx = robots[j].x - p.x, dy = robots[j].y - p.y;
    if (j != self && dx * dx + dy * dy <= robot_reach * robot_reach) near_robots_.push_back(robots[j]);
  }
  // One sine and cosine per reading: the 21 ray directions are the robot's heading turned by the
  // fixed angles in ray_directions().
  const double c = std::cos(p.theta), s = std::sin(p.theta);
  const RayDirections& dirs = ray_directions();
  IrReadings out{};
  for (std::size_t i = 0; i < kIrCount; ++i) {
    const thymio::IrMount& m = kIrMounts[i];
    const double sx = p.x + c * m.x - s * m.y, sy = p.y + s * m.x + c * m.y;
    double d[3];
    for (int k = 0; k < 3; ++k) {
      const auto [rc, rs] = dirs[i][k];
      d[k] = ray(sx, sy, c * rc - s * rs, s * rc + c * rs);
    }
    const double left = d[0], centre = d[1], right = d[2];
    double v = response(left) + response(centre) + response(right) - 2 * response(centre / std::cos(kAperture));
    v = std::clamp(v + noise.normal(0, kNoiseSd), 0.0, kM);
    out[i] = static_cast<float>(v);
  }
  return out;
}

}  // namespace symb::sim
