#include "symb/sim/ir_model.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
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

// What a ray of a sensor of a robot at p can hit lies within kRange + 1 of the sensor, and every
// sensor within kMountReach of p: so within kReach of p.
constexpr double kReach = IrModel::kRange + 1 + kMountReach;
constexpr double kRobotReach = IrModel::kRobotRadius + kReach;  // of another robot's centre

// Squared distance from (px, py) to the segment from a to b.
double distance2_to_segment(double px, double py, double ax, double ay, double bx, double by) {
  const double ex = bx - ax, ey = by - ay;
  const double len2 = ex * ex + ey * ey;
  double t = len2 > 0 ? ((px - ax) * ex + (py - ay) * ey) / len2 : 0;
  t = std::clamp(t, 0.0, 1.0);
  const double dx = ax + t * ex - px, dy = ay + t * ey - py;
  return dx * dx + dy * dy;
}

// What one read keeps: on the stack up to N items (a robot among a few dozen walls and robots),
// on the heap beyond, so that reads share nothing and allocate only in the rare crowded case.
template <class T, std::size_t N>
class NearList {
 public:
  void push(const T& v) {
    if (size_ < N) {
      fixed_[size_] = v;
    } else {
      if (size_ == N) spill_.assign(fixed_.begin(), fixed_.end());
      spill_.push_back(v);
    }
    ++size_;
  }
  std::span<const T> items() const { return size_ <= N ? std::span<const T>(fixed_.data(), size_) : spill_; }

 private:
  std::array<T, N> fixed_;
  std::size_t size_ = 0;
  std::vector<T> spill_;
};

GridBox around(const Pose& p, double reach) { return {p.x - reach, p.y - reach, p.x + reach, p.y + reach}; }

}  // namespace

IrModel::IrModel(std::vector<Rect> walls) {
  edges_.reserve(4 * walls.size());
  for (const Rect& r : walls) {
    const double c = std::cos(r.angle), s = std::sin(r.angle);
    const double lx = c * r.half_length, ly = s * r.half_length;  // along
    const double wx = -s * r.half_width, wy = c * r.half_width;   // across
    const double xs[4] = {r.cx + lx + wx, r.cx - lx + wx, r.cx - lx - wx, r.cx + lx - wx};
    const double ys[4] = {r.cy + ly + wy, r.cy - ly + wy, r.cy - ly - wy, r.cy + ly - wy};
    for (int i = 0; i < 4; ++i) edges_.push_back({xs[i], ys[i], xs[(i + 1) % 4], ys[(i + 1) % 4]});
  }
  std::vector<GridBox> boxes;
  boxes.reserve(edges_.size());
  GridBox area{};
  for (const Segment& e : edges_) {
    boxes.push_back({std::min(e.x1, e.x2), std::min(e.y1, e.y2), std::max(e.x1, e.x2), std::max(e.y1, e.y2)});
    const GridBox& b = boxes.back();
    area = boxes.size() == 1 ? b
                             : GridBox{std::min(area.min_x, b.min_x), std::min(area.min_y, b.min_y),
                                       std::max(area.max_x, b.max_x), std::max(area.max_y, b.max_y)};
  }
  // Cells as wide as a read's reach; few enough that walls crossing a huge arena stay cheap to
  // index (a query then meets more edges, each rejected by one distance test).
  edge_grid_.layout(area, kReach, std::max<std::size_t>(4096, 16 * edges_.size()));
  edge_grid_.set_boxes(boxes);
}

void IrModel::set_robots(std::span<const Pose> robots) {
  robots_.assign(robots.begin(), robots.end());
  // Over where the robots are (wherever physics put them), a few cells per robot at most.
  robot_grid_.layout(SpatialGrid::bounds(robots_), kRobotReach, 4 * robots_.size() + 64);
  robot_grid_.set_points(robots_);
}

double IrModel::ray(double px, double py, double ux, double uy, std::span<const Segment> edges,
                    std::span<const Point> robots) {
  double best = kRange + 1;  // beyond range: no response
  for (const Segment& e : edges) best = std::min(best, hit_segment(px, py, ux, uy, e.x1, e.y1, e.x2, e.y2, best));
  for (const Point& robot : robots) {
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

IrReadings IrModel::read(std::size_t self, kernel::RandomStream& noise) const {
  if (self >= robots_.size())
    throw std::out_of_range("ir model: no robot " + std::to_string(self) + " (" + std::to_string(robots_.size()) +
                            " set)");
  const Pose& p = robots_[self];
  // Each ray keeps the nearest hit, so leaving out edges and robots that no ray can reach changes
  // nothing; a non-finite pose fails every test, as nothing is near it.
  NearList<Segment, 64> near_edges;
  edge_grid_.for_each(around(p, kReach), [&](std::size_t i) {
    const Segment& e = edges_[i];
    if (distance2_to_segment(p.x, p.y, e.x1, e.y1, e.x2, e.y2) <= kReach * kReach) near_edges.push(e);
  });
  NearList<Point, 32> near_robots;
  robot_grid_.for_each(around(p, kRobotReach), [&](std::size_t j) {
    const double dx = robots_[j].x - p.x, dy = robots_[j].y - p.y;
    if (j != self && dx * dx + dy * dy <= kRobotReach * kRobotReach) near_robots.push({robots_[j].x, robots_[j].y});
  });
  const std::span<const Segment> edges = near_edges.items();
  const std::span<const Point> robots = near_robots.items();
  // One sine and cosine per reading: the 21 ray directions are the robot's heading turned by the
  // fixed angles in ray_directions().
  const double c = std::cos(p.theta), s = std::sin(p.theta);
  const RayDirections& dirs = ray_directions();
  // With nothing near, every ray reaches kRange + 1 and every response is 0 (most robots of a
  // sparse swarm, most of the time): only the noise is left to draw.
  const bool clear = edges.empty() && robots.empty();
  IrReadings out{};
  for (std::size_t i = 0; i < kIrCount; ++i) {
    double v = 0;
    if (!clear) {
      const thymio::IrMount& m = kIrMounts[i];
      const double sx = p.x + c * m.x - s * m.y, sy = p.y + s * m.x + c * m.y;
      double d[3];
      for (int k = 0; k < 3; ++k) {
        const auto [rc, rs] = dirs[i][k];
        d[k] = ray(sx, sy, c * rc - s * rs, s * rc + c * rs, edges, robots);
      }
      const double left = d[0], centre = d[1], right = d[2];
      v = response(left) + response(centre) + response(right) - 2 * response(centre / std::cos(kAperture));
    }
    v = std::clamp(v + noise.normal(0, kNoiseSd), 0.0, kM);
    out[i] = static_cast<float>(v);
  }
  return out;
}

std::vector<IrModel::Rect> IrModel::walls_of(const WorldSpec& spec) {
  std::vector<Rect> rects;
  rects.reserve(4 + spec.walls.size());
  const double w = spec.width, h = spec.height, t = 10;
  rects.push_back({w / 2, -t / 2, w / 2 + t, t / 2, 0});
  rects.push_back({w / 2, h + t / 2, w / 2 + t, t / 2, 0});
  rects.push_back({-t / 2, h / 2, t / 2, h / 2 + t, 0});
  rects.push_back({w + t / 2, h / 2, t / 2, h / 2 + t, 0});
  for (const WallSpec& s : spec.walls) {
    const double dx = s.x2 - s.x1, dy = s.y2 - s.y1;
    const double length = std::hypot(dx, dy);
    const double angle = length > 0 ? std::atan2(dy, dx) : 0.0;
    rects.push_back({(s.x1 + s.x2) / 2, (s.y1 + s.y2) / 2, (length + s.thickness) / 2, s.thickness / 2, angle});
  }
  return rects;
}

}  // namespace symb::sim
