#include "symb/apps/run/run_recorder.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>

namespace symb::apps::run {

namespace {

// A wheel speed below this (cm/s) does not count as moving.
constexpr double kMovingSpeed = 1.0;
// Fewer path points per robot in a crowd, so the picture stays a few MB at most.
constexpr double kCrowdPointSpacing = 1.0;  // cm

}  // namespace

RunRecorder::RunRecorder(const sim::World& world, std::ostream* csv, std::uint32_t csv_every, double dt)
    : csv_(csv), csv_every_(csv_every), dt_(dt) {
  const std::size_t n = world.robot_count();
  paths_.resize(n);
  summaries_.resize(n);
  was_in_contact_.assign(n, false);
  for (std::size_t i = 0; i < n; ++i) {
    paths_[i].name = world.robot_name(i);
    summaries_[i].name = world.robot_name(i);
    const sim::RobotState s = world.state(i);
    paths_[i].points.push_back({s.pose.x, s.pose.y});
  }
  if (csv_) {
    *csv_ << "time_s,robot,x_cm,y_cm,heading_rad";
    for (std::size_t k = 0; k < sim::kIrCount; ++k) *csv_ << ",ir" << k;
    *csv_ << ",left_cm_s,right_cm_s,contact\n";
  }
}

void RunRecorder::on_step(const sim::StepRecord& record) {
  const std::uint64_t step = steps_++;
  const bool write_row = csv_ && step % csv_every_ == 0;
  const bool crowd = paths_.size() > 10;
  char buf[96];
  for (std::size_t i = 0; i < paths_.size(); ++i) {
    const sim::RobotState& s = record.robots[i].state;
    for (double v : {s.pose.x, s.pose.y, s.pose.theta, s.left_speed, s.right_speed})
      mix(std::bit_cast<std::uint64_t>(v));
    RobotSummary& sum = summaries_[i];
    sum.distance = s.distance;
    sum.contact_steps = s.contact_steps;
    sum.end = s.pose;
    if (std::max(std::fabs(s.left_speed), std::fabs(s.right_speed)) > kMovingSpeed) sum.moving_seconds += dt_;
    auto& points = paths_[i].points;
    if (!crowd || std::hypot(s.pose.x - points.back().x, s.pose.y - points.back().y) >= kCrowdPointSpacing)
      points.push_back({s.pose.x, s.pose.y});
    if (s.in_contact && !was_in_contact_[i]) {
      ++sum.contact_events;
      paths_[i].contacts.push_back({s.pose.x, s.pose.y});
    }
    was_in_contact_[i] = s.in_contact;
    if (write_row) {
      std::snprintf(buf, sizeof buf, "%.3f,", static_cast<double>(record.step) * dt_);
      *csv_ << buf << paths_[i].name;
      std::snprintf(buf, sizeof buf, ",%.3f,%.3f,%.4f", s.pose.x, s.pose.y, s.pose.theta);
      *csv_ << buf;
      for (float v : record.robots[i].ir) {
        std::snprintf(buf, sizeof buf, ",%.1f", static_cast<double>(v));
        *csv_ << buf;
      }
      std::snprintf(buf, sizeof buf, ",%.3f,%.3f,%d\n", s.left_speed, s.right_speed, s.in_contact ? 1 : 0);
      *csv_ << buf;
    }
  }
}

void RunRecorder::mix(std::uint64_t word) {
  for (int b = 0; b < 8; ++b) {
    hash_ ^= (word >> (8 * b)) & 0xff;
    hash_ *= 0x100000001b3ULL;
  }
}

}  // namespace symb::apps::run
