#include "symb/robot/sensor.hpp"

#include <charconv>
#include <stdexcept>

#include "symb/io/number_text.hpp"
#include "symb/kernel/counter.hpp"
#include "symb/kernel/prefetch.hpp"
#include "symb/os/node.hpp"
#include "symb/robot/ports.hpp"

namespace symb::robot {

using kernel::Error;

// --- Sensor ----------------------------------------------------------------------------------------

Sensor::Sensor(std::string name, std::vector<ChannelSpec> channels, Options options)
    : io::Device(std::move(name)),
      mu_(options.threads == DeviceThreads::kAny),
      ranges_(ranges_of(channels)),  // declared before channels_: made from the argument
      mailbox_capacity_(options.mailbox),
      channels_(std::move(channels)) {
  if (auto st = validate_channels(channels_); !st)
    throw std::invalid_argument("sensor '" + this->name() + "': " + st.error());
  if (options.mailbox == 0)
    throw std::invalid_argument("sensor '" + this->name() + "': mailbox must hold at least one sample");
  add_ioctl({"channels", std::nullopt, "the channels: name [min, max] units, one per line"},
            [this](const os::ParamValue*) {
              std::string text;
              for (const auto& c : channels_) text += describe(c) + "\n";
              return kernel::Result<std::string>(text);
            });
  add_ioctl({"latest", std::nullopt, "the newest accepted sample: time in ns, then one value per channel"},
            [this](const os::ParamValue*) -> kernel::Result<std::string> {
              auto s = latest();
              if (!s) return Error{"sensor '" + this->name() + "' has no sample yet"};
              return std::to_string(s->time.count()) + " " + io::format_numbers(s->numbers());
            });
  add_ioctl({"stats", std::nullopt, "publish counters"}, [this](const os::ParamValue*) {
    const SensorStats s = stats();
    return kernel::Result<std::string>(
        "published=" + std::to_string(s.published) + " not_open=" + std::to_string(s.not_open) +
        " rejected=" + std::to_string(s.rejected) + " unheard=" + std::to_string(s.unheard) +
        " queued=" + std::to_string(s.queued_total) + " taken=" + std::to_string(s.taken) +
        " overwritten=" + std::to_string(s.overwritten) + " clamped_values=" + std::to_string(s.clamped_values));
  });
}

Sensor::~Sensor() = default;

kernel::Status Sensor::open() {
  std::lock_guard lock(open_mu_);
  if (open_.load()) return {};
  if (auto st = activate(); !st) return Error{"sensor '" + name() + "' did not open: " + st.error()};
  open_.store(true, std::memory_order_release);
  return {};
}

void Sensor::close() {
  std::lock_guard lock(open_mu_);
  if (!open_.load()) return;
  open_.store(false, std::memory_order_release);
  deactivate();
}

PublishResult Sensor::publish(std::span<const float> values, std::shared_ptr<const os::Blob> blob, kernel::Time time) {
  SensorSample s;
  s.time = time;
  s.blob = std::move(blob);
  std::lock_guard lock(mu_);
  ++stats_.published;
  if (!open_.load(std::memory_order_acquire)) {
    ++stats_.not_open;
    return PublishResult::kNotOpen;
  }
  const Conditioned c = condition_sample(ranges_, values, s.values);
  PublishResult result = PublishResult::kQueued;
  if (!c.ok()) {
    ++stats_.rejected;
    result = PublishResult::kRejected;
  } else {
    s.count = static_cast<std::uint8_t>(ranges_.size());
    stats_.clamped_values += c.clamped;
    latest_ = s;
    if (!notify_) {
      ++stats_.unheard;
      return PublishResult::kUnheard;
    }
    ++stats_.queued_total;
    if (mailbox_->push_overwrite(s)) ++stats_.overwritten;  // attach() made it
  }
  // A rejection wakes the task too, so that it can log it; one notification per drain.
  if (notify_ && !notified_) {
    notified_ = true;
    notify_();
  }
  return result;
}

SensorStats Sensor::stats() const {
  std::lock_guard lock(mu_);
  return stats_;
}

std::optional<SensorSample> Sensor::latest() const {
  std::lock_guard lock(mu_);
  return latest_;
}

bool Sensor::has_listener() const { return listening_.load(std::memory_order_acquire); }

void Sensor::prefetch(int level) const {
  if (level == 0) {
    kernel::prefetch_bytes(this, sizeof(*this));
    return;
  }
  if (!ranges_.empty()) kernel::prefetch_bytes(ranges_.data(), ranges_.size() * sizeof(ChannelRange));
  if (listening_.load(std::memory_order_relaxed)) kernel::prefetch_bytes(&mailbox_->front(), sizeof(SensorSample));
}

void SensorTask::prefetch(int level) const {
  if (level == 0) kernel::prefetch_bytes(this, sizeof(*this));
  sensor_->prefetch(level);
}

kernel::Status Sensor::attach(std::function<void()> notify) {
  std::lock_guard lock(mu_);
  if (notify_) return Error{"sensor '" + name() + "' already feeds a task"};
  if (!mailbox_) mailbox_.emplace(mailbox_capacity_);
  notify_ = std::move(notify);
  notified_ = false;
  listening_.store(true, std::memory_order_release);
  on_listener_changed(true);
  return {};
}

void Sensor::detach() {
  std::lock_guard lock(mu_);
  notify_ = nullptr;
  listening_.store(false, std::memory_order_release);
  on_listener_changed(false);
  // Whatever the task did not take is now unheard; keeping it would hand stale samples to the
  // next task as fresh ones.
  if (mailbox_) {
    stats_.overwritten += mailbox_->size();
    mailbox_->clear();
  }
  notified_ = false;
}

SensorStats Sensor::take(std::span<SensorSample> out, std::size_t* taken) {
  std::size_t n = 0;
  std::lock_guard lock(mu_);
  notified_ = false;
  if (mailbox_)
    // Copied once, straight into `out` (take() would copy it out, then into `out`).
    while (n < out.size() && !mailbox_->empty()) {
      out[n++] = mailbox_->front();
      mailbox_->pop();
    }
  stats_.taken += n;
  *taken = n;
  return stats_;
}

// --- SensorTask ------------------------------------------------------------------------------------

// What a notification needs to find the task. Owned by the task alone: injected work holds it
// weakly, so work still queued in a virtual-time executor after the task is gone does nothing
// (and so never touches a node that may be gone too).
struct SensorTask::Link : std::enable_shared_from_this<Link> {
  os::Node* node = nullptr;
  os::TaskId self;
};

SensorTask::SensorTask(std::shared_ptr<Sensor> sensor, Options options)
    : sensor_(std::move(sensor)),
      options_(std::move(options)),
      link_(std::make_shared<Link>()),
      clamp_warning_(options_.warn_interval),
      reject_warning_(options_.warn_interval),
      overwrite_warning_(options_.warn_interval) {
  bind_parameters(options_);
  if (!sensor_) throw std::invalid_argument("sensor task: no sensor");
  // Its notifier runs inside publish(): at once only where that holds no lock the drain takes.
  if (sensor_->threads() == DeviceThreads::kOneAtATime) take_notifications_at_once();
  if (!options_.ranges.empty()) {
    if (options_.ranges.size() != sensor_->channels().size())
      throw std::invalid_argument("sensor task: " + std::to_string(options_.ranges.size()) + " ranges for " +
                                  std::to_string(sensor_->channels().size()) + " channels of '" + sensor_->name() +
                                  "'");
    if (auto st = validate_channels(options_.ranges); !st) throw std::invalid_argument("sensor task: " + st.error());
  }
}

SensorTask::~SensorTask() {
  // on_stop detached; this covers a task destroyed without running it.
  if (attached_) sensor_->detach();
}

SensorTaskStats SensorTask::stats() const { return {forwarded_.load(), clamped_.load(), rejected_.load()}; }

void SensorTask::on_start() {
  link_->node = &node();
  link_->self = id();
  if (!sensor_->is_open())
    if (auto st = sensor_->open(); !st) log(os::LogLevel::kWarn, st.error());
  const SensorStats counted = sensor_->stats();
  seen_ = {counted.clamped_values, counted.rejected, counted.overwritten};
  // The notifier runs inside publish(), under the sensor's lock (or, for a device called one
  // context at a time, on that context), and the task detaches in on_stop under that same lock:
  // while it runs, the task, the link and the node it names are alive. It captures two pointers,
  // so std::function keeps it without a heap block of its own: the task and its node's executor,
  // asked directly (through the link and the node, two more loads from memory in a swarm).
  auto st = sensor_->attach([self = this, context = &node().executor()] {
    // A simulated device publishes on the executor's own context: the notification is made at
    // once, exactly where the injected one would have run, before any later event; the task is
    // running (it detaches in on_stop, under the lock this runs under), so it needs no lookup.
    if (context->on_own_context()) {
      self->notify();
      return;
    }
    Link* link = self->link_.get();
    link->node->inject([weak = link->weak_from_this()] {
      if (auto alive = weak.lock()) (void)alive->node->notify(alive->self);
    });
  });
  if (!st) {
    log(os::LogLevel::kError, st.error() + ": this task forwards nothing");
    return;
  }
  attached_ = true;
}

void SensorTask::on_stop() {
  if (attached_) sensor_->detach();
  attached_ = false;
}

void SensorTask::on_notify() { drain(); }

void SensorTask::drain() {
  // On the stack, which is in the cache, rather than a buffer of the task's own, which in a
  // swarm of thousands is not by the time the task runs again; a fuller mailbox takes more rounds.
  // At most a mailbox's worth per wake: a driver publishing as fast as the task forwards cannot
  // keep it here for ever, and what it published meanwhile has rearmed the notification.
  std::array<SensorSample, 4> batch;
  std::size_t n = 0;
  SensorStats after = sensor_->take(batch, &n);
  forward(std::span<const SensorSample>(batch.data(), n));
  for (std::size_t total = n; n == batch.size() && total < sensor_->mailbox_capacity_; total += n) {
    after = sensor_->take(batch, &n);
    forward(std::span<const SensorSample>(batch.data(), n));
  }
  report(after);
}

void SensorTask::forward(std::span<const SensorSample> samples) {
  std::array<float, os::Payload::kInlineValues> narrowed;
  for (const SensorSample& s : samples) {
    if (s.blob) {
      // Rare (a camera's frame): the message is built here to carry the blob too.
      os::Payload payload(std::span<const float>(s.numbers()));
      if (!options_.ranges.empty()) {
        const Conditioned c = condition_sample(options_.ranges, s.numbers(), narrowed);
        if (!c.ok()) {
          rejected_.bump();
          continue;
        }
        if (c.clamped > 0) clamped_.bump(c.clamped);
        payload.assign(std::span<const float>(narrowed.data(), s.count));
      }
      payload.blob = s.blob;
      send(kDataPort, payload);
    } else if (options_.ranges.empty()) {
      send(kDataPort, s.numbers());
    } else {
      const Conditioned c = condition_sample(options_.ranges, s.numbers(), narrowed);
      if (!c.ok()) {
        rejected_.bump();
        continue;
      }
      if (c.clamped > 0) clamped_.bump(c.clamped);
      send(kDataPort, std::span<const float>(narrowed.data(), s.count));
    }
    forwarded_.bump();
  }
}

void SensorTask::report(const SensorStats& st) {
  const kernel::Time t = now();
  const std::uint64_t clamped = st.clamped_values - seen_.clamped_values;
  const std::uint64_t rejected = st.rejected - seen_.rejected;
  const std::uint64_t overwritten = st.overwritten - seen_.overwritten;
  seen_ = {st.clamped_values, st.rejected, st.overwritten};
  if (clamped > 0 && clamp_warning_.note(t, clamped))
    log(os::LogLevel::kWarn, std::to_string(clamp_warning_.count()) + " value(s) of '" + sensor_->name() +
                                 "' outside their channel range, clamped");
  if (rejected > 0 && reject_warning_.note(t, rejected))
    log(os::LogLevel::kWarn, std::to_string(reject_warning_.count()) + " sample(s) of '" + sensor_->name() +
                                 "' rejected (NaN or wrong number of values)");
  if (overwritten > 0 && overwrite_warning_.note(t, overwritten))
    log(os::LogLevel::kWarn, std::to_string(overwrite_warning_.count()) + " sample(s) of '" + sensor_->name() +
                                 "' lost: the mailbox was full before this task ran");
}

kernel::Status SensorTask::on_parameter_changed(std::string_view /*name: warn_interval*/) {
  clamp_warning_.set_interval(options_.warn_interval);
  reject_warning_.set_interval(options_.warn_interval);
  overwrite_warning_.set_interval(options_.warn_interval);
  return {};
}

}  // namespace symb::robot
