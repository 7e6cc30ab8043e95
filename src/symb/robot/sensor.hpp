// Sensor and SensorTask: the paper's active sensor, one that "informs the system that new data
// arrived by generating a hardware/software interrupt". The driver owns the timing: whenever it
// has a sample (an interrupt fired, a reader thread decoded a frame) it calls Sensor::publish()
// from whatever thread it runs on. A SensorTask attached to the sensor makes that data hookable:
// every sample is sent, one number per channel, on kDataPort to the tasks hooked to it.
//
// Design:
//  - The Sensor is a device (open, close, typed ioctls) holding its channel specs and a small
//    mailbox of samples. publish() conditions the sample (NaN: rejected; out of range: clamped),
//    queues it and, like an interrupt handler giving a semaphore, notifies the task once; more
//    samples before the task runs just join the mailbox. A full mailbox drops its oldest sample
//    (counted): for sensor data only the newest matters.
//  - The notification is a Node::notify (no message), made at once when the driver runs on the
//    executor's own context (a simulated device) and otherwise handed over through Node::inject,
//    the one node call a foreign thread may make under every executor; so the same code runs
//    under the thread executor (at once, on the driver's thread) and under the virtual-time one
//    (between events, on its thread). The task then drains the mailbox on its own context. For a
//    device called one context at a time (no data lock around the notifier) the task takes its
//    notifications at once (Task::take_notifications_at_once): the drain runs inside publish()
//    when its activation would have been the next event anyway.
//  - Every counter is exact: published == not_open + rejected + unheard + queued_total, and
//    queued_total == taken + overwritten + (samples still in the mailbox).
//  - Samples published while no task listens are unheard: kept as latest() only, never queued,
//    so a task that starts later does not forward stale data as fresh.
//  - A sensor feeds one SensorTask at a time; hooks give any number of receivers.
//  - Forwarded messages carry the node time at which the task sent them (Task::send stamps every
//    message); the driver's own sample time is kept with latest().
//  - Drivers either hold a Sensor and call publish(), or derive from it to start and stop the
//    hardware with the device (activate() on open, deactivate() on close).
//  - A sample may carry a shared blob beside its numbers (a camera's frame, depth_image.hpp): the
//    task sends both in one message, and every receiver shares the one blob.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "symb/io/device.hpp"
#include "symb/kernel/counter.hpp"
#include "symb/kernel/optional_mutex.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/ring_buffer.hpp"
#include "symb/kernel/time.hpp"
#include "symb/os/message.hpp"
#include "symb/os/task.hpp"
#include "symb/os/warning_limiter.hpp"
#include "symb/robot/channel_spec.hpp"
#include "symb/robot/device_threads.hpp"

namespace symb::robot {

// One conditioned reading of every channel, with the instant the driver gave for it.
struct SensorSample {
  kernel::Time time{0};
  std::uint8_t count = 0;
  // Before the numbers, as in os::Payload: a copy of a few numbers then touches one run of bytes
  // (two cache lines, not three, in a swarm whose sensors are all out of the cache at each step).
  std::shared_ptr<const os::Blob> blob;  // null for most sensors
  // Only values[0, count) is ever read; copies move just those (a sample is built and copied
  // three times per reading, with 7 of its 32 numbers in use for the IR).
  std::array<float, os::Payload::kInlineValues> values;

  SensorSample() = default;
  SensorSample(const SensorSample& o) : time(o.time), count(o.count), blob(o.blob) {
    os::copy_numbers(values.data(), o.values.data(), count);
  }
  SensorSample& operator=(const SensorSample& o) {
    time = o.time;
    count = o.count;
    os::copy_numbers(values.data(), o.values.data(), count);
    blob = o.blob;
    return *this;
  }
  ~SensorSample() = default;

  std::span<const float> numbers() const { return {values.data(), count}; }
};

struct SensorStats {
  std::uint64_t published = 0;       // publish() calls
  std::uint64_t not_open = 0;        // published while the device was closed: dropped
  std::uint64_t rejected = 0;        // wrong number of values or a NaN: dropped
  std::uint64_t unheard = 0;         // accepted while no task listened: kept as latest() only
  std::uint64_t queued_total = 0;    // put into the mailbox for the task
  std::uint64_t taken = 0;           // taken from the mailbox by the task
  std::uint64_t overwritten = 0;     // pushed out of a full mailbox, or left in it when the task detached
  std::uint64_t clamped_values = 0;  // values moved into their channel's range (in accepted samples)
};

// What publish() did with a sample.
enum class PublishResult : std::uint8_t { kQueued, kUnheard, kRejected, kNotOpen };

class Sensor : public io::Device {
 public:
  struct Options {
    std::size_t mailbox = 8;                      // samples held for the task between two of its runs (>= 1)
    DeviceThreads threads = DeviceThreads::kAny;  // kOneAtATime: no data lock (device_threads.hpp)
  };

  // Throws std::invalid_argument on a bad channel list (see validate_channels): a driver's
  // channel table is fixed when it is written, not input to be recovered from.
  Sensor(std::string name, std::vector<ChannelSpec> channels) : Sensor(std::move(name), std::move(channels), {}) {}
  Sensor(std::string name, std::vector<ChannelSpec> channels, Options options);
  ~Sensor() override;

  const std::vector<ChannelSpec>& channels() const { return channels_; }

  // Starts the device (activate()); a sample is only accepted while it is open.
  kernel::Status open() override;
  void close() override;
  bool is_open() const override { return open_.load(std::memory_order_acquire); }

  // For the driver, from any thread (one context at a time for DeviceThreads::kOneAtATime), at
  // any time (the "interrupt"): one value per channel, sampled at `time`. Never blocks for long
  // (a short lock), never throws.
  PublishResult publish(std::span<const float> values, kernel::Time time) { return publish(values, nullptr, time); }
  // ... with a blob that travels with the numbers (a rejected sample drops it too).
  PublishResult publish(std::span<const float> values, std::shared_ptr<const os::Blob> blob, kernel::Time time);

  SensorStats stats() const;
  // The newest accepted sample, heard or not.
  std::optional<SensorSample> latest() const;
  // Whether a SensorTask is attached (samples are queued, not unheard).
  bool has_listener() const;
  DeviceThreads threads() const { return mu_.enabled() ? DeviceThreads::kAny : DeviceThreads::kOneAtATime; }
  // A hint with no effect on behaviour (os::Task::prefetch): asks the memory system for what
  // publishing and taking samples read: level 0 this object, level 1 (a while later) the channel
  // ranges and the mailbox's head. From the thread that takes the samples (the head is its own).
  void prefetch(int level) const;

 protected:
  // Driver hooks, called outside the sensor's data lock (a driver may publish from inside).
  virtual kernel::Status activate() { return {}; }
  virtual void deactivate() {}
  // Driver hook: a task started (true) or stopped (false) taking this sensor's samples, as
  // has_listener() now says. Called with the data lock held: note it, call nothing back.
  virtual void on_listener_changed(bool /*listening*/) {}

 private:
  friend class SensorTask;
  // The notifier runs inside publish(), on the driver's thread, with the sensor's lock held: it
  // may only hand work over (Node::inject), never call back into the sensor.
  kernel::Status attach(std::function<void()> notify);
  void detach();
  // Moves up to out.size() samples out of the mailbox, oldest first, into out[0, *taken), and
  // rearms the notification. Returns the counters as they were then (one lock for both: a task
  // drains every period). Fewer than out.size() taken: the mailbox is empty.
  SensorStats take(std::span<SensorSample> out, std::size_t* taken);

  // What every publish() reads and writes comes first, together (in a swarm each robot's sensor is
  // out of the cache at each step); the channels and the open/close lock after.
  std::atomic<bool> open_{false};
  // Mirrors `notify_ != nullptr` for has_listener(), which a simulator asks every step.
  std::atomic<bool> listening_{false};
  mutable kernel::OptionalMutex mu_;  // the fields from here to latest_; off for DeviceThreads::kOneAtATime
  bool notified_ = false;
  const std::vector<ChannelRange> ranges_;  // the channels' ranges, packed: what publish() reads
  // Made at the first attach: a sensor no task listens to (a simulated robot's pose and ground
  // drivers, in most scenarios) keeps only its latest sample.
  std::optional<kernel::RingBuffer<SensorSample>> mailbox_;
  std::function<void()> notify_;
  SensorStats stats_;
  std::optional<SensorSample> latest_;
  std::size_t mailbox_capacity_;
  const std::vector<ChannelSpec> channels_;
  std::mutex open_mu_;  // serialises open/close (and the driver's activate/deactivate)
};

struct SensorTaskStats {
  std::uint64_t forwarded = 0;       // samples sent to hooked tasks
  std::uint64_t clamped_values = 0;  // values clamped by the task's own (narrower) ranges
  std::uint64_t rejected = 0;        // samples that did not fit the task's ranges (channel count)
};

class SensorTask : public os::Task {
 public:
  struct Options {
    // Narrower ranges than the device's (same channels), or empty for the device's own.
    std::vector<ChannelSpec> ranges;
    kernel::Duration warn_interval = std::chrono::seconds(1);
  };

  // Throws std::invalid_argument when `ranges` does not match the sensor's channels.
  explicit SensorTask(std::shared_ptr<Sensor> sensor) : SensorTask(std::move(sensor), Options{}) {}
  SensorTask(std::shared_ptr<Sensor> sensor, Options options);
  ~SensorTask() override;

  Sensor& sensor() { return *sensor_; }
  // Safe from any thread.
  SensorTaskStats stats() const;
  void prefetch(int level) const override;

 protected:
  void on_start() override;
  void on_notify() override;
  void on_stop() override;
  kernel::Status on_parameter_changed(std::string_view name) override;

 private:
  struct Link;
  void drain();
  // Sends each sample (narrowed to the task's ranges, when it has its own).
  void forward(std::span<const SensorSample> samples);
  void report(const SensorStats& now_seen);

  // The sensor's counters that report() warns of, as they were at its last call.
  struct Seen {
    std::uint64_t clamped_values = 0, rejected = 0, overwritten = 0;
  };

  // What every drain reads, together in the object's first lines (in a swarm each robot's task is
  // out of the cache at each step); the rest after.
  std::shared_ptr<Sensor> sensor_;
  kernel::Counter forwarded_;  // kernel/counter.hpp, as clamped_ and rejected_
  Options options_;
  Seen seen_;
  bool attached_ = false;
  std::shared_ptr<Link> link_;
  os::WarningLimiter clamp_warning_;
  os::WarningLimiter reject_warning_;
  os::WarningLimiter overwrite_warning_;
  kernel::Counter clamped_, rejected_;
};

}  // namespace symb::robot
