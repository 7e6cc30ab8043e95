#include "symb/apps/run/run_recorder.hpp"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <numeric>

#include "symb/apps/run/steps_csv.hpp"
#include "symb/apps/run/steps_h5.hpp"

namespace symb::apps::run {

namespace {

// A wheel speed below this (cm/s) does not count as moving.
constexpr double kMovingSpeed = 1.0;
// Fewer path points per robot in a crowd, so the picture stays a few MB at most.
constexpr double kCrowdPointSpacing = 1.0;  // cm
constexpr std::size_t kNoPath = static_cast<std::size_t>(-1);

std::vector<std::size_t> all_of(std::size_t n) {
  std::vector<std::size_t> v(n);
  std::iota(v.begin(), v.end(), std::size_t{0});
  return v;
}

}  // namespace

RunRecorder::RunRecorder(const sim::World& world, std::ostream* csv, std::uint32_t csv_every, double dt)
    : RunRecorder(
          world,
          RecorderSetup{.csv = csv, .h5 = nullptr, .every = csv_every, .robots = {}, .paths = {}, .density = false},
          dt) {}

RunRecorder::RunRecorder(const sim::World& world, RecorderSetup setup, double dt) : setup_(std::move(setup)), dt_(dt) {
  const std::size_t n = world.robot_count();
  summaries_.resize(n);
  was_in_contact_.assign(n, false);
  for (std::size_t i = 0; i < n; ++i) summaries_[i].name = world.robot_name(i);
  row_robots_ = setup_.robots ? *setup_.robots : all_of(n);
  const std::vector<std::size_t> kept = setup_.paths ? *setup_.paths : all_of(n);
  path_of_.assign(n, kNoPath);
  for (std::size_t i : kept) {
    path_of_[i] = paths_.size();
    RobotPath& p = paths_.emplace_back();
    p.name = world.robot_name(i);
    const sim::RobotState s = world.state(i);
    p.points.push_back({s.pose.x, s.pose.y});
  }
  crowd_paths_ = paths_.size() > 10;
  if (setup_.density) density_.emplace(world.spec().width, world.spec().height, kDensityCells);
  if (setup_.every == 0) setup_.every = 1;
  if (setup_.csv) {
    const std::string header = steps_csv_header();
    setup_.csv->write(header.data(), static_cast<std::streamsize>(header.size()));
    csv_bytes_ += header.size();
  }
}

void RunRecorder::on_step(const sim::StepRecord& record) {
  // Timed only when steps are written (the summary reports the time then): two clock reads a
  // step were a fifth of the recorder's own cost in a run that writes nothing.
  const bool timed = setup_.csv != nullptr || setup_.h5 != nullptr;
  const auto started = timed ? std::chrono::steady_clock::now() : std::chrono::steady_clock::time_point{};
  const std::uint64_t step = steps_++;
  for (std::size_t i = 0; i < summaries_.size(); ++i) {
    const sim::RobotState& s = record.robots[i].state;
    for (double v : {s.pose.x, s.pose.y, s.pose.theta, s.left_speed, s.right_speed})
      mix(std::bit_cast<std::uint64_t>(v));
    RobotSummary& sum = summaries_[i];
    sum.distance = s.distance;
    sum.contact_steps = s.contact_steps;
    sum.end = s.pose;
    if (std::max(std::fabs(s.left_speed), std::fabs(s.right_speed)) > kMovingSpeed) sum.moving_seconds += dt_;
    const bool contact_begins = s.in_contact && !was_in_contact_[i];
    if (contact_begins) ++sum.contact_events;
    was_in_contact_[i] = s.in_contact;
    if (density_) density_->add(s.pose.x, s.pose.y);
    if (path_of_[i] == kNoPath) continue;
    RobotPath& path = paths_[path_of_[i]];
    auto& points = path.points;
    if (!crowd_paths_ || std::hypot(s.pose.x - points.back().x, s.pose.y - points.back().y) >= kCrowdPointSpacing)
      points.push_back({s.pose.x, s.pose.y});
    if (contact_begins) path.contacts.push_back({s.pose.x, s.pose.y});
  }
  if (step % setup_.every == 0 && (setup_.csv || setup_.h5)) {
    ++recorded_;
    const double time_s = static_cast<double>(record.step) * dt_;
    if (setup_.csv) {
      row_text_.clear();
      for (std::size_t i : row_robots_) append_steps_csv_row(row_text_, time_s, summaries_[i].name, record.robots[i]);
      setup_.csv->write(row_text_.data(), static_cast<std::streamsize>(row_text_.size()));
      csv_bytes_ += row_text_.size();
    }
    if (setup_.h5) setup_.h5->append(record, time_s);
  }
  if (timed) seconds_spent_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
}

void RunRecorder::mix(std::uint64_t word) {
  // A word at a time (a byte at a time was 40 steps per number, for each robot at every step);
  // the shift folds the high bits down, which a multiplication alone never moves.
  hash_ = (hash_ ^ word) * 0x100000001b3ULL;
  hash_ ^= hash_ >> 29;
}

}  // namespace symb::apps::run
