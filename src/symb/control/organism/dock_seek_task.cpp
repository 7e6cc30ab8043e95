#include "symb/control/organism/dock_seek_task.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "symb/os/node.hpp"

namespace symb::control::organism {

namespace {

double seconds(kernel::Duration d) { return std::chrono::duration<double>(d).count(); }

// Thresholds of the phases, from the self-assembly exploration (docs/organism.md).
constexpr double kAtPredock = 0.025;      // m from the pre-dock point: turn to face the target
constexpr double kFacing = 0.05;          // rad: face to face enough to go in
constexpr double kOffLine = 0.04;         // m off the target's normal line: start over
constexpr double kOffHeading = 0.25;      // rad off face to face while docking: start over
constexpr double kLatchDistance = 0.025;  // m: latch within this (and aligned) ...
constexpr double kLatchHeading = 0.15;    // ... and this (rad): else it might be another's connector
constexpr double kTooNear = 0.06;         // m: something this near ahead that is not the target

}  // namespace

std::array<double, 2> DockSeeker::wheels(const SeekOutput& out) const {
  double l = out.v - out.w * o_.half_track, r = out.v + out.w * o_.half_track;
  const double m = std::max({std::abs(l), std::abs(r), o_.max_speed}) / o_.max_speed;
  return {l / m, r / m};
}

SeekOutput DockSeeker::step(const SeekInput& in, double dt, double wander) {
  SeekOutput out;
  if (in.state >= 2) {
    phase_ = SeekPhase::kDocked;
    return out;
  }
  if (phase_ == SeekPhase::kDocked) phase_ = SeekPhase::kSearch;  // undocked by someone: seek again
  const bool seen = in.distance >= 0;
  auto back_off = [&](double speed, double turn) {
    if (phase_ == SeekPhase::kBackOff) return;
    resume_ = seen ? SeekPhase::kApproach : SeekPhase::kSearch;
    phase_ = SeekPhase::kBackOff;
    in_phase_ = 0;
    backoff_speed_ = speed;
    backoff_turn_ = turn;
  };
  // Stuck: commanded to move for a whole window, yet neither the beacon nor the gyro moved.
  window_ += dt;
  turned_ += std::abs(in.gyro_z) * dt;
  if (seen && window_distance_ < 0) window_distance_ = in.distance;
  if (window_ >= seconds(o_.stuck_time)) {
    const double moved = seen && window_distance_ >= 0 ? std::abs(in.distance - window_distance_) : 0.0;
    if (commanded_ && turned_ < 0.05 && moved < 0.01 && phase_ != SeekPhase::kBackOff) back_off(-0.07, 1.0);
    window_ = turned_ = 0;
    window_distance_ = -1;
    commanded_ = false;
  }
  if (phase_ == SeekPhase::kBackOff) {
    in_phase_ += dt;
    if (in_phase_ < seconds(o_.backoff_time)) {
      out = {backoff_speed_, backoff_turn_, false};
      commanded_ = backoff_speed_ != 0;
      return out;
    }
    phase_ = resume_;
    in_phase_ = 0;
  }
  if (!seen) {
    if (phase_ != SeekPhase::kSearch) {
      phase_ = SeekPhase::kSearch;
      in_phase_ = 0;
    }
    // A scan on the spot, then a short drive somewhere else.
    const double spin = seconds(o_.search_spin), drive = seconds(o_.search_drive);
    if (in_phase_ >= spin + drive) in_phase_ = 0;
    if (in_phase_ < spin) {
      out.w = search_turn_;  // towards where a beacon was seen last
    } else {
      if (in_phase_ - dt < spin) wander_ = wander;
      out.v = 0.1;
      out.w = wander_;
    }
    in_phase_ += dt;
    commanded_ = true;
    return out;
  }
  if (phase_ == SeekPhase::kSearch) phase_ = SeekPhase::kApproach;
  search_turn_ = in.bearing < 0 ? -1.0 : 1.0;
  if (in.front_ir && *in.front_ir < kTooNear && *in.front_ir < in.distance - 0.03) {
    // Another seeker (or the chain's side) nearer than the target: reverse, turning, and retry.
    // (Standing still to let another seeker finish docking was tried: fewer seeds assembled,
    // docs/organism.md.)
    back_off(-0.07, 0.8);
    out = {backoff_speed_, backoff_turn_, false};
    commanded_ = backoff_speed_ != 0;
    return out;
  }
  // The target and its outward normal in my frame (x ahead of my connector), then the pre-dock
  // point seen from my wheel axle.
  const double tx = in.distance * std::cos(in.bearing), ty = in.distance * std::sin(in.bearing);
  const double nx = -std::cos(in.heading), ny = -std::sin(in.heading);
  const double out_along = o_.predock + o_.axle;
  const double px = tx + out_along * nx + o_.axle, py = ty + out_along * ny;
  const double lateral = -(tx * ny - ty * nx);
  if (phase_ == SeekPhase::kApproach && std::hypot(px, py) < kAtPredock) phase_ = SeekPhase::kAlign;
  if (phase_ == SeekPhase::kAlign && std::abs(in.heading) < kFacing) phase_ = SeekPhase::kDock;
  if (phase_ == SeekPhase::kDock && (std::abs(in.heading) > kOffHeading || std::abs(lateral) > kOffLine))
    phase_ = SeekPhase::kApproach;
  if (phase_ == SeekPhase::kApproach) {
    const double rp = std::hypot(px, py), ap = std::atan2(py, px);
    if (std::abs(ap) <= std::numbers::pi / 2) {
      behind_turn_ = 0;
      out.v = std::min(0.12, 1.5 * rp) * std::cos(ap);
      out.w = 3 * ap;
    } else if (in.distance > o_.predock || std::abs(in.bearing) > std::numbers::pi / 2 || behind_turn_ != 0) {
      // The pre-dock point behind me, the target off to one side: turn on the spot towards the
      // target until the point is ahead, so the target stays in the beacon's cone (turning the
      // other way loses it and the search turns me back: a livelock). The side is kept until
      // then, so a bearing near 0 or pi does not make it dither.
      if (behind_turn_ == 0) behind_turn_ = in.bearing < 0 ? -1 : 1;
      out.w = 1.5 * behind_turn_;
    } else {
      // The pre-dock point behind me, the target ahead (too close, or came in crooked): reverse
      // onto the pre-dock point, steering by my back.
      const double back = std::remainder(ap - std::numbers::pi, 2 * std::numbers::pi);
      out.v = -std::min(0.08, 1.5 * rp) * std::abs(std::cos(ap));
      out.w = 3 * back;
    }
  } else if (phase_ == SeekPhase::kAlign) {
    out.w = std::clamp(6 * in.heading, -1.0, 1.0);
    if (std::abs(out.w) < 0.25) out.w = out.w < 0 ? -0.25 : 0.25;
  } else {
    out.v = 0.05;
    out.w = 4 * in.bearing + 2 * in.heading;
  }
  out.latch = in.state == 1 && in.distance < kLatchDistance && std::abs(in.heading) < kLatchHeading;
  commanded_ = true;
  return out;
}

DockSeekTask::DockSeekTask(DockSeekOptions options, DeviceLookup devices)
    : o_(std::move(options)), devices_(std::move(devices)), seeker_(o_) {}

DockSeekStats DockSeekTask::stats() const {
  return DockSeekStats{.readings = counters_.readings.load(),
                       .ignored = counters_.ignored.load(),
                       .latches = counters_.latches.load(),
                       .refused = counters_.refused.load()};
}

kernel::Status DockSeekTask::ioctl(const std::string& device, const std::string& command) {
  std::shared_ptr<io::Device> d = devices_ ? devices_(device) : nullptr;
  if (!d) return kernel::Error{"no device named '" + device + "' on this robot"};
  auto reply = d->ioctl(command, "");
  if (!reply) return kernel::Error{reply.error()};
  return {};
}

void DockSeekTask::on_start() {
  // Free: the back stays closed, so no other seeker docks to a module that is not in the chain.
  if (auto st = ioctl(o_.back, "close"); !st) log(os::LogLevel::kWarn, "closing the back: " + st.error());
}

void DockSeekTask::on_message(const os::Message& m) {
  const auto v = m.numbers();
  const auto from = [&](const std::string& task) {
    const auto id = node().find(task);
    return id && *id == m.source;
  };
  const bool finite = os::all_finite(v);
  if (m.payload.blob || !finite) {
    counters_.ignored.bump();
    return;
  }
  if (v.size() >= 6 && from(o_.connector)) {
    in_.state = static_cast<int>(std::lround(v[0]));
    in_.distance = v[3];
    in_.bearing = v[4];
    in_.heading = v[5];
  } else if (v.size() >= 1 && from(o_.ir)) {
    in_.front_ir = v[0] > 0 ? std::optional<double>((1.0 - v[0]) * o_.ir_range) : std::nullopt;
  } else if (v.size() >= 6 && from(o_.imu)) {
    in_.gyro_z = v[5];
  } else {
    counters_.ignored.bump();
    return;
  }
  counters_.readings.bump();
}

void DockSeekTask::on_tick() {
  const kernel::Time t = now();
  const double dt = last_tick_ ? std::chrono::duration<double>(t - *last_tick_).count() : 0.0;
  last_tick_ = t;
  const SeekOutput out = seeker_.step(in_, dt, random().uniform(-1.0, 1.0));
  phase_.store(static_cast<int>(seeker_.phase()), std::memory_order_relaxed);
  if (out.latch) {
    if (auto st = ioctl(o_.connector, "latch"); st) {
      counters_.latches.bump();
      in_.state = 2;  // the next reading says so too; stop now
    } else {
      counters_.refused.bump();
      if (warning_.note(t)) log(os::LogLevel::kInfo, "latch refused: " + st.error());
    }
  }
  if (seeker_.phase() == SeekPhase::kDocked || in_.state >= 2) {
    // In the chain now: its back becomes the next target.
    if (!back_opened_) {
      back_opened_ = true;
      if (auto st = ioctl(o_.back, "open"); !st) log(os::LogLevel::kWarn, "opening the back: " + st.error());
    }
    send(0, {0.0f, 0.0f});
  } else {
    const auto w = seeker_.wheels(out);
    const double k = 500.0 / o_.max_speed;
    send(0, {static_cast<float>(w[0] * k), static_cast<float>(w[1] * k)});
  }
  if (probing())
    probe("dock_seek", {static_cast<float>(seeker_.phase()), static_cast<float>(out.v), static_cast<float>(out.w),
                        static_cast<float>(in_.distance)});
}

}  // namespace symb::control::organism
