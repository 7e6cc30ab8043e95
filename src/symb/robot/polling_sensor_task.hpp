// PollingSensor and PollingSensorTask: the paper's passive sensor, one that "has to be polled"
// (an ADC, a TWI slave). The task owns the timing: at its period (TaskOptions::period) it asks the
// driver for a fresh sample and sends it, one number per channel, on kDataPort to the tasks
// hooked to it.
//
// Design:
//  - PollingSensor is the driver's interface: a device with channel specs and poll(now, out).
//    poll() runs on the task's own context, so it must not block (read a register, return the
//    last conversion); hardware that must be waited for belongs to an active Sensor with a
//    thread of its own.
//  - A poll that fails sends nothing: receivers never get stale data as if it were fresh. The
//    output buffer is filled with NaN before each poll, so a driver that claims success but
//    leaves a channel unwritten is caught as a NaN sample and rejected as well.
//  - Out-of-range values are clamped, NaN samples rejected (ChannelSpec); failures, rejections
//    and clamps are counted exactly and logged at a limited rate (WarningLimiter).
//  - A closed device is not reopened behind the back of whoever closed it: the task opens it
//    once when it starts, and afterwards counts polls of a closed device as failures.
#pragma once

#include <array>
#include <atomic>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "symb/io/device.hpp"
#include "symb/kernel/counter.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"
#include "symb/os/message.hpp"
#include "symb/os/task.hpp"
#include "symb/os/warning_limiter.hpp"
#include "symb/robot/channel_spec.hpp"

namespace symb::robot {

class PollingSensor : public io::Device {
 public:
  // Throws std::invalid_argument on a bad channel list (see validate_channels).
  PollingSensor(std::string name, std::vector<ChannelSpec> channels);

  const std::vector<ChannelSpec>& channels() const { return channels_; }

  // Writes one fresh value per channel into `out` (out.size() == channels().size()), sampled as
  // of `now` (the polling task's node time). An error means there is no fresh sample this time.
  // Called from the polling task's context only; must not block.
  virtual kernel::Status poll(kernel::Time now, std::span<float> out) = 0;

  // A plain open flag; drivers that must start hardware override these.
  kernel::Status open() override;
  void close() override;
  bool is_open() const override { return open_.load(std::memory_order_acquire); }

 private:
  const std::vector<ChannelSpec> channels_;
  std::atomic<bool> open_{false};
};

struct PollingStats {
  std::uint64_t ticks = 0;                 // polls attempted
  std::uint64_t sent = 0;                  // samples sent to hooked tasks
  std::uint64_t failed = 0;                // poll() errors and polls of a closed device
  std::uint64_t rejected = 0;              // samples with a NaN (or an unwritten channel)
  std::uint64_t clamped_values = 0;        // values moved into their channel's range
  std::uint64_t consecutive_failures = 0;  // failed or rejected polls since the last good one
};

class PollingSensorTask : public os::Task {
 public:
  struct Options {
    // Ranges to condition with instead of the driver's (same channels), or empty.
    std::vector<ChannelSpec> ranges;
    kernel::Duration warn_interval = std::chrono::seconds(1);
  };

  // Throws std::invalid_argument when there is no driver or `ranges` does not match its channels.
  explicit PollingSensorTask(std::shared_ptr<PollingSensor> sensor) : PollingSensorTask(std::move(sensor), Options{}) {}
  PollingSensorTask(std::shared_ptr<PollingSensor> sensor, Options options);

  PollingSensor& sensor() { return *sensor_; }
  // Safe from any thread.
  PollingStats stats() const;

 protected:
  void on_start() override;
  void on_tick() override;
  kernel::Status on_parameter_changed(std::string_view name) override;

 private:
  void failed(const std::string& why);

  std::shared_ptr<PollingSensor> sensor_;
  Options options_;
  std::span<const ChannelSpec> specs_;  // options_.ranges or the driver's
  std::array<float, os::Payload::kInlineValues> raw_{};
  std::array<float, os::Payload::kInlineValues> out_{};
  os::WarningLimiter fail_warning_;
  os::WarningLimiter reject_warning_;
  os::WarningLimiter clamp_warning_;
  kernel::Counter ticks_, sent_, failed_, rejected_, clamped_, consecutive_;  // kernel/counter.hpp
};

}  // namespace symb::robot
