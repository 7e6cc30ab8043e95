// Actuator and ActuatorSinkTask: the paper's standard actuator, one that "changes the robot's
// state immediately" (LEDs, a buzzer's volume, a motor's raw PWM). set() applies a value per
// channel at once through the driver; an ActuatorSinkTask makes an actuator hookable, applying
// every message it receives.
//
// Design:
//  - Actuator is a device with channel specs; drivers derive from it and implement apply().
//    set() conditions the command first (ChannelSpec): values out of range are clamped, and a
//    command with a NaN or the wrong number of values is rejected as a whole, so the previous
//    output stays on the hardware. A half-applied command (three LEDs of four) is never seen.
//  - output() is what the hardware was last told, which is what the shell shows.
//  - set() is thread-safe (a task and the shell may both drive one LED bar); commands are
//    applied one at a time, in the order they take the actuator's lock.
//  - The sink counts and logs (at a limited rate) what it had to clamp or reject; it never
//    faults on bad input.
#pragma once

#include <array>
#include <atomic>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include "symb/io/device.hpp"
#include "symb/kernel/result.hpp"
#include "symb/os/message.hpp"
#include "symb/os/task.hpp"
#include "symb/robot/channel_spec.hpp"
#include "symb/robot/warning_limiter.hpp"

namespace symb::robot {

struct ActuatorStats {
  std::uint64_t commands = 0;        // set() calls
  std::uint64_t applied = 0;         // commands that reached the hardware
  std::uint64_t rejected = 0;        // NaN or wrong count: nothing applied
  std::uint64_t not_open = 0;        // commands while closed: nothing applied
  std::uint64_t driver_errors = 0;   // apply() failed
  std::uint64_t clamped_values = 0;  // values moved into their channel's range
};

class Actuator : public io::Device {
 public:
  // Throws std::invalid_argument on a bad channel list (see validate_channels).
  Actuator(std::string name, std::vector<ChannelSpec> channels);

  const std::vector<ChannelSpec>& channels() const { return channels_; }

  // Conditions and applies one value per channel, now. Returns how many values were clamped, or
  // an error (NaN, wrong count, closed device, driver failure) after which output() is unchanged.
  kernel::Result<std::size_t> set(std::span<const float> values);
  // The values last applied; before the first set(), each channel's range-clamped zero.
  std::vector<float> output() const;
  ActuatorStats stats() const;

  // A plain open flag; drivers that must start hardware override these.
  kernel::Status open() override;
  void close() override;
  bool is_open() const override { return open_.load(std::memory_order_acquire); }

 protected:
  // The driver: put `values` (conditioned, one per channel) on the hardware. Called with the
  // actuator's lock held, on the caller's thread (a task's context, the shell); must not block.
  virtual kernel::Status apply(std::span<const float> values) = 0;

 private:
  const std::vector<ChannelSpec> channels_;
  std::atomic<bool> open_{false};
  mutable std::mutex mu_;  // output_, stats_ and the driver's apply()
  std::vector<float> output_;
  std::vector<float> staged_;
  ActuatorStats stats_;
};

struct ActuatorSinkStats {
  std::uint64_t received = 0;  // messages handled
  std::uint64_t applied = 0;   // commands the actuator took
  std::uint64_t failed = 0;    // commands it refused (see the actuator's stats for why)
  std::uint64_t ignored = 0;   // messages without numbers (a blob)
};

class ActuatorSinkTask : public os::Task {
 public:
  struct Options {
    // Narrower ranges than the actuator's own (same channels), or empty.
    std::vector<ChannelSpec> ranges;
    kernel::Duration warn_interval = std::chrono::seconds(1);
  };

  // Throws std::invalid_argument when there is no actuator or `ranges` does not match it.
  explicit ActuatorSinkTask(std::shared_ptr<Actuator> actuator) : ActuatorSinkTask(std::move(actuator), Options{}) {}
  ActuatorSinkTask(std::shared_ptr<Actuator> actuator, Options options);

  Actuator& actuator() { return *actuator_; }
  // Safe from any thread.
  ActuatorSinkStats stats() const;

 protected:
  void on_start() override;
  void on_message(const os::Message& m) override;
  kernel::Status on_parameter(std::string_view name, const os::ParamValue& value) override;

 private:
  std::shared_ptr<Actuator> actuator_;
  Options options_;
  std::array<float, os::Payload::kInlineValues> narrowed_{};
  WarningLimiter fail_warning_;
  WarningLimiter clamp_warning_;
  std::atomic<std::uint64_t> received_{0}, applied_{0}, failed_{0}, ignored_{0};
};

}  // namespace symb::robot
