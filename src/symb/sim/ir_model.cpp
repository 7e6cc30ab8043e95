#include "symb/sim/ir_model.hpp"

#include <algorithm>
#include <cmath>

namespace symb::sim {

namespace {

struct SensorMount {
  double x, y, orientation;  // on the robot, cm and radians
};
// Enki's Thymio2 layout: 0 far left ... 4 far right, 5 back left, 6 back right.
constexpr SensorMount kMounts[kIrCount] = {
    {6.2, 4.85, 0.69813},   {7.5, 2.55, 0.34906}, {7.95, 0.0, 0.0},      {7.5, -2.55, -0.34906},
    {6.2, -4.85, -0.69813}, {-2.95, 2.95, -M_PI}, {-2.95, -2.95, -M_PI},
};
constexpr double kM = 4505, kX0 = 0.03, kC = 73, kNoiseSd = 2.87;
constexpr double kAperture = 15.0 * M_PI / 180.0;

double response(double x) {
  if (x < kX0) return kM;
  if (x > IrModel::kRange) return 0;
  return kM * (kC - kX0 * kX0) / (x * x - 2 * kX0 * x + kC);
}

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

double IrModel::ray(double px, double py, double angle, std::size_t self, std::span<const Pose> robots) const {
  const double ux = std::cos(angle), uy = std::sin(angle);
  double best = kRange + 1;  // beyond range: no response
  for (const Wall& w : walls_) {
    if (std::hypot(w.cx - px, w.cy - py) > w.reach + kRange) continue;
    for (const Segment& e : w.edges) best = std::min(best, hit_segment(px, py, ux, uy, e.x1, e.y1, e.x2, e.y2, best));
  }
  for (std::size_t j = 0; j < robots.size(); ++j) {
    if (j == self) continue;
    const double dx = robots[j].x - px, dy = robots[j].y - py;
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
  const double c = std::cos(p.theta), s = std::sin(p.theta);
  IrReadings out{};
  for (std::size_t i = 0; i < kIrCount; ++i) {
    const SensorMount& m = kMounts[i];
    const double sx = p.x + c * m.x - s * m.y, sy = p.y + s * m.x + c * m.y;
    const double a = p.theta + m.orientation;
    const double centre = ray(sx, sy, a, self, robots);
    const double left = ray(sx, sy, a + kAperture, self, robots);
    const double right = ray(sx, sy, a - kAperture, self, robots);
    double v = response(left) + response(centre) + response(right) - 2 * response(centre / std::cos(kAperture));
    v = std::clamp(v + noise.normal(0, kNoiseSd), 0.0, kM);
    out[i] = static_cast<float>(v);
  }
  return out;
}

}  // namespace symb::sim
