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
//    applied one at a time, in the order they take the actuator's lock. An actuator made
//    DeviceThreads::kOneAtATime (a simulated robot's, under a non-concurrent executor) has no lock
//    and is called from one context at a time.
//  - The sink takes its messages at once (os::Task::take_messages_at_once): under virtual time a
//    command is applied inside the sender's send, not at an activation of its own after the
//    sender's handler; what the world sees at its next step is the same. A command sent at the
//    instant a watchdog tick is due therefore counts as heard by that tick.
//  - The sink counts and logs (at a limited rate) what it had to clamp or reject; it never
//    faults on bad input.
//  - The sink's watchdog (Options::timeout, 0 = off): when no command has been applied for
//    `timeout`, the sink applies the safe output (each channel's value closest to 0 within its
//    range, the sink's narrower ranges if it has them) once, counts it and warns at a limited
//    rate; the next command is applied as usual. So when the controller stops sending (suspended
//    from the shell, faulted, deleted), the wheels stop. The check runs at the sink's ticks: the
//    task needs a period (the actuator_sink type's default is 10 ms), and the wheels stop at the
//    first tick at least `timeout` after the last applied command, so within timeout + period.
//    A tick that finds the deadline ahead skips the ticks before it (Task::skip_ticks_before):
//    while commands flow the sink ticks about once a timeout, on the same grid, at the same
//    instants it would have acted at. The timer starts when the task starts; a refused command
//    (NaN, wrong count) does not feed it.
#pragma once

#include <array>
#include <atomic>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include "symb/io/device.hpp"
#include "symb/kernel/counter.hpp"
#include "symb/kernel/optional_mutex.hpp"
#include "symb/kernel/result.hpp"
#include "symb/os/message.hpp"
#include "symb/os/task.hpp"
#include "symb/os/warning_limiter.hpp"
#include "symb/robot/channel_spec.hpp"
#include "symb/robot/device_threads.hpp"

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
  // `threads`: kOneAtATime skips the data lock (device_threads.hpp).
  Actuator(std::string name, std::vector<ChannelSpec> channels, DeviceThreads threads = DeviceThreads::kAny);

  const std::vector<ChannelSpec>& channels() const { return channels_; }

  // Conditions and applies one value per channel, now. Returns how many values were clamped, or
  // an error (NaN, wrong count, closed device, driver failure) after which output() is unchanged.
  kernel::Result<std::size_t> set(std::span<const float> values);
  // The values last applied; before the first set(), each channel's range-clamped zero.
  std::vector<float> output() const;
  ActuatorStats stats() const;
  DeviceThreads threads() const { return mu_.enabled() ? DeviceThreads::kAny : DeviceThreads::kOneAtATime; }

  // A plain open flag; drivers that must start hardware override these.
  kernel::Status open() override;
  void close() override;
  bool is_open() const override { return open_.load(std::memory_order_acquire); }

 protected:
  // The driver: put `values` (conditioned, one per channel) on the hardware. Called with the
  // actuator's lock held, on the caller's thread (a task's context, the shell); must not block.
  virtual kernel::Status apply(std::span<const float> values) = 0;
  // The lock apply() runs under. A driver whose state written by apply() is read from elsewhere (a
  // simulator taking the newest command at its step) reads it under this lock too, rather than
  // taking a lock of its own inside this one at every command.
  kernel::OptionalMutex& apply_mutex() const { return mu_; }

 private:
  const std::vector<ChannelSpec> channels_;
  const std::vector<ChannelRange> ranges_;  // channels_' ranges, packed: what set() reads
  std::atomic<bool> open_{false};
  mutable kernel::OptionalMutex mu_;  // output_, stats_ and the driver's apply(); off for kOneAtATime
  std::vector<float> output_;
  ActuatorStats stats_;
};

struct ActuatorSinkStats {
  std::uint64_t received = 0;  // messages handled
  std::uint64_t applied = 0;   // commands the actuator took
  std::uint64_t failed = 0;    // commands it refused (see the actuator's stats for why)
  std::uint64_t ignored = 0;   // messages without numbers (a blob)
  std::uint64_t timeouts = 0;  // watchdog expiries: the safe output was applied
};

class ActuatorSinkTask : public os::Task {
 public:
  struct Options {
    // Narrower ranges than the actuator's own (same channels), or empty.
    std::vector<ChannelSpec> ranges;
    kernel::Duration warn_interval = std::chrono::seconds(1);
    // Watchdog: apply the safe output when no command was applied for this long; 0: off. Needs
    // a period to be checked at ticks; without one the sink gives itself a third of the timeout.
    kernel::Duration timeout{0};
  };

  // Throws std::invalid_argument when there is no actuator, `ranges` does not match it, or the
  // timeout is negative.
  explicit ActuatorSinkTask(std::shared_ptr<Actuator> actuator) : ActuatorSinkTask(std::move(actuator), Options{}) {}
  ActuatorSinkTask(std::shared_ptr<Actuator> actuator, Options options);

  Actuator& actuator() { return *actuator_; }
  // What the watchdog applies: each channel's value closest to 0 within its range.
  std::vector<float> safe_output() const;
  // Safe from any thread.
  ActuatorSinkStats stats() const;
  void prefetch(int level) const override;

 protected:
  void on_start() override;
  void on_message(const os::Message& m) override;
  void on_tick() override;
  kernel::Status on_parameter_changed(std::string_view name) override;

 private:
  // Gives a task with a timeout and no period of its own ticks to watch it; with `restart`, a
  // task that has a period starts its tick chain afresh (see on_parameter_changed).
  void arm_watchdog(bool restart);

  // What every command and watchdog tick reads first, together in the object's first lines (in
  // a swarm each robot's sink is out of the cache at each step); the rest after.
  std::shared_ptr<Actuator> actuator_;
  Options options_;
  kernel::Time last_applied_{0};  // the watchdog's reference: start, last applied command
  bool timed_out_ = false;        // the safe output is on since the last expiry
  kernel::Counter received_, applied_, failed_, ignored_, timeouts_;  // kernel/counter.hpp
  std::array<float, os::Payload::kInlineValues> narrowed_{};
  os::WarningLimiter fail_warning_;
  os::WarningLimiter clamp_warning_;
  os::WarningLimiter timeout_warning_;
};

}  // namespace symb::robot
