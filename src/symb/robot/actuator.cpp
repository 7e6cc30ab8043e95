#include "symb/robot/actuator.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <stdexcept>

#include "symb/io/number_text.hpp"
#include "symb/kernel/counter.hpp"
#include "symb/kernel/prefetch.hpp"
#include "symb/os/node.hpp"

namespace symb::robot {

using kernel::Error;

// --- Actuator --------------------------------------------------------------------------------------

Actuator::Actuator(std::string name, std::vector<ChannelSpec> channels, DeviceThreads threads)
    : io::Device(std::move(name)),
      channels_(std::move(channels)),
      ranges_(ranges_of(channels_)),
      mu_(threads == DeviceThreads::kAny) {
  if (auto st = validate_channels(channels_); !st)
    throw std::invalid_argument("actuator '" + this->name() + "': " + st.error());
  output_.resize(channels_.size());
  for (std::size_t i = 0; i < channels_.size(); ++i) output_[i] = channels_[i].clamp(0.0f);
  add_ioctl({"channels", std::nullopt, "the channels: name [min, max] units, one per line"},
            [this](const os::ParamValue*) {
              std::string text;
              for (const auto& c : channels_) text += describe(c) + "\n";
              return kernel::Result<std::string>(text);
            });
  add_ioctl({"output", std::nullopt, "the values last applied, one per channel"},
            [this](const os::ParamValue*) { return kernel::Result<std::string>(io::format_numbers(output())); });
  add_ioctl(
      {"set", os::ParamSpec{"values", os::ParamType::kString, std::string(), 1.0, 1024.0, "one number per channel"},
       "applies values now (clamped to range; NaN or a wrong count is refused)"},
      [this](const os::ParamValue* arg) -> kernel::Result<std::string> {
        auto v = io::parse_numbers(std::get<std::string>(*arg));
        if (!v) return Error{v.error()};
        auto r = set(*v);
        if (!r) return Error{r.error()};
        return io::format_numbers(output());
      });
  add_ioctl({"stats", std::nullopt, "command counters"}, [this](const os::ParamValue*) {
    const ActuatorStats s = stats();
    return kernel::Result<std::string>(
        "commands=" + std::to_string(s.commands) + " applied=" + std::to_string(s.applied) +
        " rejected=" + std::to_string(s.rejected) + " not_open=" + std::to_string(s.not_open) +
        " driver_errors=" + std::to_string(s.driver_errors) + " clamped_values=" + std::to_string(s.clamped_values));
  });
}

kernel::Status Actuator::open() {
  open_.store(true, std::memory_order_release);
  return {};
}

void Actuator::close() { open_.store(false, std::memory_order_release); }

kernel::Result<std::size_t> Actuator::set(std::span<const float> values) {
  std::lock_guard lock(mu_);
  ++stats_.commands;
  if (!is_open()) {
    ++stats_.not_open;
    return Error{"actuator '" + name() + "' is closed"};
  }
  // Conditioned on the stack (a device has at most a message's worth of channels,
  // validate_channels): a buffer of the actuator's own is one more cache line to fetch per
  // command in a swarm.
  std::array<float, os::Payload::kInlineValues> buffer;
  const std::span<float> staged(buffer.data(), ranges_.size());
  const Conditioned c = condition_sample(ranges_, values, staged);
  if (!c.ok()) {
    ++stats_.rejected;
    if (c.fault == SampleFault::kWrongCount)
      return Error{"actuator '" + name() + "' takes " + std::to_string(channels_.size()) + " values, not " +
                   std::to_string(values.size())};
    return Error{"actuator '" + name() + "': NaN for channel '" + channels_[c.channel].name + "'"};
  }
  // Made in place (a Status assigned after its construction moves a string every command).
  const kernel::Status st = [&]() -> kernel::Status {
    try {
      return apply(staged);
    } catch (const std::exception& e) {
      return Error{std::string("driver threw: ") + e.what()};
    }
  }();
  if (!st) {
    // The hardware state is unknown now; output() keeps what we last know was applied.
    ++stats_.driver_errors;
    return Error{"actuator '" + name() + "': " + st.error()};
  }
  std::copy(staged.begin(), staged.end(), output_.begin());
  ++stats_.applied;
  stats_.clamped_values += c.clamped;
  return c.clamped;
}

std::vector<float> Actuator::output() const {
  std::lock_guard lock(mu_);
  return output_;
}

ActuatorStats Actuator::stats() const {
  std::lock_guard lock(mu_);
  return stats_;
}

// --- ActuatorSinkTask ------------------------------------------------------------------------------

ActuatorSinkTask::ActuatorSinkTask(std::shared_ptr<Actuator> actuator, Options options)
    : actuator_(std::move(actuator)),
      options_(std::move(options)),
      fail_warning_(options_.warn_interval),
      clamp_warning_(options_.warn_interval),
      timeout_warning_(options_.warn_interval) {
  bind_parameters(options_);
  // on_message acts on the actuator alone: a command is applied inside its sender's send.
  take_messages_at_once();
  if (!actuator_) throw std::invalid_argument("actuator sink: no actuator");
  if (options_.timeout.count() < 0) throw std::invalid_argument("actuator sink: negative timeout");
  if (!options_.ranges.empty()) {
    if (options_.ranges.size() != actuator_->channels().size())
      throw std::invalid_argument("actuator sink: " + std::to_string(options_.ranges.size()) + " ranges for " +
                                  std::to_string(actuator_->channels().size()) + " channels of '" + actuator_->name() +
                                  "'");
    if (auto st = validate_channels(options_.ranges); !st) throw std::invalid_argument("actuator sink: " + st.error());
  }
}

void ActuatorSinkTask::prefetch(int level) const {
  // The watchdog's state is in the object, past its first lines; the actuator is a block of its own.
  if (level == 0) {
    kernel::prefetch_bytes(this, sizeof(*this));
    kernel::prefetch_bytes(actuator_.get(), 2 * kernel::kCacheLine);
  }
}

ActuatorSinkStats ActuatorSinkTask::stats() const {
  return {received_.load(), applied_.load(), failed_.load(), ignored_.load(), timeouts_.load()};
}

std::vector<float> ActuatorSinkTask::safe_output() const {
  const auto& channels = options_.ranges.empty() ? actuator_->channels() : options_.ranges;
  std::vector<float> out(channels.size());
  for (std::size_t i = 0; i < channels.size(); ++i) out[i] = channels[i].clamp(0.0f);
  return out;
}

// The watchdog is checked at ticks. A sink without a watchdog needs none, so the type's default
// period is 0; one with a watchdog and no period of its own gets ticks at a third of the timeout,
// which stops the outputs within 4/3 of the timeout.
void ActuatorSinkTask::arm_watchdog(bool restart) {
  const auto info = node().info(id());
  if (!info) return;
  if (info->period.count() > 0) {
    if (restart) (void)node().set_period(id(), info->period);
  } else if (options_.timeout.count() > 0) {
    (void)node().set_period(id(), std::max<kernel::Duration>(options_.timeout / 3, std::chrono::milliseconds(1)));
  }
}

void ActuatorSinkTask::on_start() {
  last_applied_ = now();
  arm_watchdog(/*restart=*/false);
  if (!actuator_->is_open())
    if (auto st = actuator_->open(); !st)
      log(os::LogLevel::kWarn, "cannot open '" + actuator_->name() + "': " + st.error());
}

void ActuatorSinkTask::on_message(const os::Message& m) {
  received_.bump();
  if (m.payload.blob) {
    ignored_.bump();
    return;
  }
  std::span<const float> values = m.numbers();
  std::size_t narrowed_clamps = 0;
  if (!options_.ranges.empty()) {
    const Conditioned c = condition_sample(options_.ranges, values, narrowed_);
    // A fault here is passed on unnarrowed: the actuator refuses it and says why.
    if (c.ok()) {
      values = std::span<const float>(narrowed_.data(), options_.ranges.size());
      narrowed_clamps = c.clamped;
    }
  }
  auto r = actuator_->set(values);
  if (!r) {
    failed_.bump();
    if (fail_warning_.note(now()))
      log(os::LogLevel::kWarn, std::to_string(fail_warning_.count()) + " command(s) refused, latest: " + r.error() +
                                   " (previous output kept)");
    return;
  }
  applied_.bump();
  last_applied_ = now();
  timed_out_ = false;
  const std::size_t clamped = *r + narrowed_clamps;
  if (clamped > 0 && clamp_warning_.note(now(), clamped))
    log(os::LogLevel::kWarn, std::to_string(clamp_warning_.count()) + " value(s) for '" + actuator_->name() +
                                 "' outside their range, clamped");
}

void ActuatorSinkTask::on_tick() {
  if (options_.timeout.count() <= 0 || timed_out_) return;
  if (now() - last_applied_ < options_.timeout) {
    // Commands only move the deadline later, so no tick before it can find the sink silent: a
    // robot whose controller keeps talking costs the executor a tick a deadline, not a period.
    skip_ticks_before(last_applied_ + options_.timeout);
    return;
  }
  // Once per silence: re-applying every tick would bury the log and fight the shell's ioctls.
  timed_out_ = true;
  timeouts_.bump();
  const std::vector<float> safe = safe_output();
  auto r = actuator_->set(safe);
  if (timeout_warning_.note(now()))
    log(os::LogLevel::kWarn,
        std::to_string(timeout_warning_.count()) + " timeout(s): no command for " +
            std::to_string(std::chrono::duration_cast<std::chrono::milliseconds>(options_.timeout).count()) + " ms, " +
            (r ? std::string("safe output applied") : "safe output refused: " + r.error()));
}

kernel::Status ActuatorSinkTask::on_parameter_changed(std::string_view name) {
  if (name == "warn_interval") {
    fail_warning_.set_interval(options_.warn_interval);
    clamp_warning_.set_interval(options_.warn_interval);
    timeout_warning_.set_interval(options_.warn_interval);
  } else if (name == "timeout") {
    // A new timeout counts from now, so changing it never stops the wheels at once. The ticks
    // skipped for the old deadline start afresh: a shorter timeout must not wait for them.
    last_applied_ = now();
    timed_out_ = false;
    arm_watchdog(/*restart=*/true);
  }
  return {};
}

}  // namespace symb::robot
