#include "symb/robot/differential_drive.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace symb::robot {

using kernel::Error;

DifferentialDrive::DifferentialDrive(std::string name, double max_wheel_speed)
    : io::Device(std::move(name)), max_wheel_speed_(max_wheel_speed) {
  if (!std::isfinite(max_wheel_speed_) || max_wheel_speed_ <= 0)
    throw std::invalid_argument("drive '" + this->name() + "': the wheel speed limit must be finite and > 0");
  add_ioctl({"speeds", std::nullopt, "the wheel speeds last applied: left right, m/s"},
            [this](const os::ParamValue*) -> kernel::Result<std::string> {
              auto [l, r] = wheel_speeds();
              char text[64];
              std::snprintf(text, sizeof text, "%.6g %.6g", l, r);
              return std::string(text);
            });
  add_ioctl({"stop", std::nullopt, "sets both wheels to 0"},
            [this](const os::ParamValue*) -> kernel::Result<std::string> {
              if (auto st = set_wheel_speeds(0, 0); !st) return Error{st.error()};
              return std::string("0 0");
            });
}

kernel::Status DifferentialDrive::open() {
  open_.store(true, std::memory_order_release);
  return {};
}

void DifferentialDrive::close() { open_.store(false, std::memory_order_release); }

kernel::Status DifferentialDrive::set_wheel_speeds(double left, double right) {
  std::lock_guard lock(mu_);
  ++stats_.commands;
  if (!is_open()) {
    ++stats_.rejected;
    return Error{"drive '" + name() + "' is closed"};
  }
  if (std::isnan(left) || std::isnan(right)) {
    ++stats_.rejected;
    return Error{"drive '" + name() + "': NaN wheel speed"};
  }
  const double l = std::clamp(left, -max_wheel_speed_, max_wheel_speed_);
  const double r = std::clamp(right, -max_wheel_speed_, max_wheel_speed_);
  if (l != left || r != right) ++stats_.clamped;
  kernel::Status st;
  try {
    st = apply_wheel_speeds(l, r);
  } catch (const std::exception& e) {
    st = Error{std::string("driver threw: ") + e.what()};
  }
  if (!st) {
    ++stats_.driver_errors;
    return Error{"drive '" + name() + "': " + st.error()};
  }
  ++stats_.applied;
  left_ = l;
  right_ = r;
  return {};
}

std::pair<double, double> DifferentialDrive::wheel_speeds() const {
  std::lock_guard lock(mu_);
  return {left_, right_};
}

DriveStats DifferentialDrive::stats() const {
  std::lock_guard lock(mu_);
  return stats_;
}

}  // namespace symb::robot
