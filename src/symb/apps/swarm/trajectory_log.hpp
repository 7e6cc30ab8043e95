// TrajectoryLog: what the swarm demo remembers of one robot's path, in bounded memory whatever
// the run's length: every pose counts towards the path length, bounding box and wall-contact
// figures, but only every stride-th pose is kept as a point; when the points fill their capacity,
// every other one is dropped and the stride doubles. A picture of a long run thus stays as light
// as that of a short one, and the exact figures are still exact.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

namespace symb::apps::swarm {

struct TrajectoryPoint {
  float x = 0;
  float y = 0;
};

class TrajectoryLog {
 public:
  // `max_points` >= 2; `stride` >= 1 poses between kept points at first.
  explicit TrajectoryLog(std::size_t max_points = 1000, std::uint32_t stride = 10);

  void add(double x, double y, bool contact);

  // Kept points, oldest first; the newest pose is last() (kept or not).
  const std::vector<TrajectoryPoint>& points() const { return points_; }
  std::optional<TrajectoryPoint> last() const;
  std::uint64_t samples() const { return samples_; }
  std::uint64_t contact_samples() const { return contact_samples_; }
  double path_length() const { return path_length_; }
  double min_x() const { return min_x_; }
  double max_x() const { return max_x_; }
  double min_y() const { return min_y_; }
  double max_y() const { return max_y_; }

 private:
  std::size_t max_points_;
  std::uint32_t stride_;
  std::vector<TrajectoryPoint> points_;
  std::uint64_t samples_ = 0;
  std::uint64_t contact_samples_ = 0;
  double path_length_ = 0;
  double last_x_ = 0, last_y_ = 0;
  double min_x_ = 0, max_x_ = 0, min_y_ = 0, max_y_ = 0;
};

}  // namespace symb::apps::swarm
