#include "symb/apps/swarm/trajectory_log.hpp"

#include <algorithm>
#include <cmath>

namespace symb::apps::swarm {

TrajectoryLog::TrajectoryLog(std::size_t max_points, std::uint32_t stride)
    : max_points_(std::max<std::size_t>(max_points, 2)), stride_(std::max<std::uint32_t>(stride, 1)) {}

void TrajectoryLog::add(double x, double y, bool contact) {
  if (samples_ == 0) {
    min_x_ = max_x_ = x;
    min_y_ = max_y_ = y;
  } else {
    path_length_ += std::hypot(x - last_x_, y - last_y_);
    min_x_ = std::min(min_x_, x);
    max_x_ = std::max(max_x_, x);
    min_y_ = std::min(min_y_, y);
    max_y_ = std::max(max_y_, y);
  }
  last_x_ = x;
  last_y_ = y;
  if (contact) ++contact_samples_;
  if (samples_ % stride_ == 0) {
    if (points_.size() == max_points_) {
      // Keep the even-indexed points: they are exactly the ones the doubled stride would have kept.
      std::size_t w = 0;
      for (std::size_t r = 0; r < points_.size(); r += 2) points_[w++] = points_[r];
      points_.resize(w);
      stride_ *= 2;
    }
    if (samples_ % stride_ == 0) points_.push_back({static_cast<float>(x), static_cast<float>(y)});
  }
  ++samples_;
}

std::optional<TrajectoryPoint> TrajectoryLog::last() const {
  if (samples_ == 0) return std::nullopt;
  return TrajectoryPoint{static_cast<float>(last_x_), static_cast<float>(last_y_)};
}

}  // namespace symb::apps::swarm
