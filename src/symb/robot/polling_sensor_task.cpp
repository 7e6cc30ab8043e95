#include "symb/robot/polling_sensor_task.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "symb/robot/ports.hpp"

namespace symb::robot {

PollingSensor::PollingSensor(std::string name, std::vector<ChannelSpec> channels)
    : io::Device(std::move(name)), channels_(std::move(channels)) {
  if (auto st = validate_channels(channels_); !st)
    throw std::invalid_argument("polling sensor '" + this->name() + "': " + st.error());
}

kernel::Status PollingSensor::open() {
  open_.store(true, std::memory_order_release);
  return {};
}

void PollingSensor::close() { open_.store(false, std::memory_order_release); }

PollingSensorTask::PollingSensorTask(std::shared_ptr<PollingSensor> sensor, Options options)
    : sensor_(std::move(sensor)),
      options_(std::move(options)),
      fail_warning_(options_.warn_interval),
      reject_warning_(options_.warn_interval),
      clamp_warning_(options_.warn_interval) {
  bind_parameters(options_);
  if (!sensor_) throw std::invalid_argument("polling sensor task: no sensor");
  if (!options_.ranges.empty()) {
    if (options_.ranges.size() != sensor_->channels().size())
      throw std::invalid_argument("polling sensor task: " + std::to_string(options_.ranges.size()) + " ranges for " +
                                  std::to_string(sensor_->channels().size()) + " channels of '" + sensor_->name() +
                                  "'");
    if (auto st = validate_channels(options_.ranges); !st)
      throw std::invalid_argument("polling sensor task: " + st.error());
    specs_ = options_.ranges;
  } else {
    specs_ = sensor_->channels();
  }
}

PollingStats PollingSensorTask::stats() const {
  return {ticks_.load(), sent_.load(), failed_.load(), rejected_.load(), clamped_.load(), consecutive_.load()};
}

void PollingSensorTask::on_start() {
  if (!sensor_->is_open())
    if (auto st = sensor_->open(); !st)
      log(os::LogLevel::kWarn, "cannot open '" + sensor_->name() + "': " + st.error());
}

void PollingSensorTask::failed(const std::string& why) {
  failed_.bump();
  consecutive_.bump();
  if (fail_warning_.note(now()))
    log(os::LogLevel::kWarn, std::to_string(fail_warning_.count()) + " failed poll(s) of '" + sensor_->name() +
                                 "', latest: " + why + " (nothing sent)");
}

void PollingSensorTask::on_tick() {
  ticks_.bump();
  if (!sensor_->is_open()) return failed("device closed");
  const std::size_t n = specs_.size();
  const std::span<float> raw(raw_.data(), n);
  // Whatever the driver leaves unwritten stays NaN and gets the sample rejected below.
  std::fill(raw.begin(), raw.end(), std::numeric_limits<float>::quiet_NaN());
  kernel::Status st;
  try {
    st = sensor_->poll(now(), raw);
  } catch (const std::exception& e) {
    // A driver bug must not fault the task: the next poll may well succeed.
    st = kernel::Error{std::string("driver threw: ") + e.what()};
  }
  if (!st) return failed(st.error());
  const Conditioned c = condition_sample(specs_, raw, out_);
  if (!c.ok()) {
    rejected_.bump();
    consecutive_.bump();
    if (reject_warning_.note(now()))
      log(os::LogLevel::kWarn, std::to_string(reject_warning_.count()) + " sample(s) of '" + sensor_->name() +
                                   "' rejected: NaN in channel '" + specs_[c.channel].name + "' (nothing sent)");
    return;
  }
  consecutive_.reset();
  if (c.clamped > 0) {
    clamped_.bump(c.clamped);
    if (clamp_warning_.note(now(), c.clamped))
      log(os::LogLevel::kWarn, std::to_string(clamp_warning_.count()) + " value(s) of '" + sensor_->name() +
                                   "' outside their channel range, clamped");
  }
  send(kDataPort, std::span<const float>(out_.data(), n));
  sent_.bump();
}

kernel::Status PollingSensorTask::on_parameter_changed(std::string_view /*name: warn_interval*/) {
  fail_warning_.set_interval(options_.warn_interval);
  reject_warning_.set_interval(options_.warn_interval);
  clamp_warning_.set_interval(options_.warn_interval);
  return {};
}

}  // namespace symb::robot
