// DifferentialDrive: a two-wheeled base (or the two tracks of a tracked one), driven by setting a
// speed for each wheel in m/s, forward positive. It is the device a drive ActuatorTask commands;
// a driver implements apply_wheel_speeds() for real motors, a simulator or a serial link.
//
// Design: set_wheel_speeds() is the single checked entry (like Actuator::set): NaN is refused
// (the wheels keep what they had) and speeds beyond the drive's limit are clamped, whoever the
// caller is (a task, the shell), so no driver ever sees a value its motors cannot take.
#pragma once

#include <atomic>
#include <mutex>
#include <string>
#include <utility>

#include "symb/io/device.hpp"
#include "symb/kernel/result.hpp"

namespace symb::robot {

struct DriveStats {
  std::uint64_t commands = 0;       // set_wheel_speeds() calls
  std::uint64_t applied = 0;        // commands that reached the driver and succeeded
  std::uint64_t rejected = 0;       // NaN or closed: nothing applied
  std::uint64_t driver_errors = 0;  // apply_wheel_speeds() failed
  std::uint64_t clamped = 0;        // commands with a speed beyond the limit
};

class DifferentialDrive : public io::Device {
 public:
  // Throws std::invalid_argument unless max_wheel_speed is finite and > 0.
  DifferentialDrive(std::string name, double max_wheel_speed);

  double max_wheel_speed() const { return max_wheel_speed_; }
  // Clamps each speed to [-max, max] and applies both at once. Errors (NaN, closed device,
  // driver failure) leave wheel_speeds() as it was. Thread-safe; never blocks for long.
  kernel::Status set_wheel_speeds(double left, double right);
  // The speeds last applied (left, right), m/s.
  std::pair<double, double> wheel_speeds() const;
  DriveStats stats() const;

  // A plain open flag; drivers that must start hardware override these.
  kernel::Status open() override;
  void close() override;
  bool is_open() const override { return open_.load(std::memory_order_acquire); }

 protected:
  // The driver: put these (already checked) speeds on the wheels. Called with the drive's lock
  // held, on the caller's thread; must not block.
  virtual kernel::Status apply_wheel_speeds(double left, double right) = 0;

 private:
  const double max_wheel_speed_;
  std::atomic<bool> open_{false};
  mutable std::mutex mu_;
  double left_ = 0, right_ = 0;
  DriveStats stats_;
};

}  // namespace symb::robot
