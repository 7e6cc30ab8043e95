#include "symb/control/snn/spike_coding_tasks.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>

#include "symb/io/bytes.hpp"
#include "symb/os/message.hpp"

namespace symb::control {

using kernel::Error;
using namespace std::chrono_literals;

namespace {

// One rate-limited warning per interval, counting the ones it stands for.
// "N messages ignored, latest: why", at most once per interval.
void warn_ignored(os::WarningLimiter& limiter, kernel::Time now, kernel::Duration interval, const std::string& why,
                  const std::function<void(os::LogLevel, std::string_view)>& log) {
  if (!limiter.note(now, interval)) return;
  const std::uint64_t n = limiter.count();
  log(os::LogLevel::kWarn, std::to_string(n) + " message" + (n == 1 ? "" : "s") + " ignored, latest: " + why);
}

}  // namespace

kernel::Result<SpikeCoding> parse_spike_coding(std::string_view text) {
  if (text == "current") return SpikeCoding::kCurrent;
  if (text == "rate") return SpikeCoding::kRate;
  return Error{"coding must be current or rate, got '" + std::string(text.substr(0, 40)) + "'"};
}

// ---- encoder ----

kernel::Result<std::unique_ptr<SpikeEncoderTask>> SpikeEncoderTask::create(SpikeEncoderOptions options) {
  if (!std::isfinite(options.input_scale)) return Error{"input_scale must be a finite number"};
  if (!std::isfinite(options.gain) || std::fabs(options.gain) > 1000) return Error{"gain must be within +-1000"};
  if (!std::isfinite(options.max_rate) || options.max_rate < 0 || options.max_rate > 1000)
    return Error{"max_rate must be 0..1000 Hz (one event per ms at most)"};
  if (options.window < 1ms || options.window > 10s) return Error{"window must be 1ms..10s"};
  if (options.module > snn::kMaxModule) return Error{"module must be 0.." + std::to_string(snn::kMaxModule)};
  return std::unique_ptr<SpikeEncoderTask>(new SpikeEncoderTask(options));
}

SpikeCodingStats SpikeEncoderTask::stats() const { return counters_.snapshot(); }

void SpikeEncoderTask::ignore(const std::string& why) {
  counters_.ignored.bump();
  warn_ignored(warning_, now(), options_.warn_interval, why, [this](os::LogLevel l, std::string_view t) { log(l, t); });
}

void SpikeEncoderTask::on_message(const os::Message& m) {
  if (m.payload.blob) {
    ignore("a blob (a sensor vector of numbers expected)");
    return;
  }
  const std::span<const float> x = m.numbers();
  if (x.empty()) {
    ignore("an empty sensor vector");
    return;
  }
  float s[os::Payload::kInlineValues];
  for (std::size_t k = 0; k < x.size(); ++k) {
    if (!std::isfinite(x[k])) {
      ignore("a sensor vector with a non-finite value at index " + std::to_string(k));
      return;
    }
    s[k] = std::clamp(x[k] * options_.input_scale, 0.0f, 1.0f);
  }
  std::uint64_t events = 0;
  if (options_.coding == SpikeCoding::kCurrent) {
    float currents[os::Payload::kInlineValues];
    for (std::size_t k = 0; k < x.size(); ++k) currents[k] = options_.gain * s[k];
    if (probing()) probe("currents", std::span<const float>(currents, x.size()));
    send(0, std::span<const float>(currents, x.size()));
  } else {
    std::vector<snn::AerEvent> out;
    const std::int64_t ms = options_.window.count() / 1'000'000;
    const std::int64_t now_us = now().count() / 1000;
    for (std::int64_t t = 0; t < ms; ++t)
      for (std::size_t k = 0; k < x.size(); ++k)
        if (random().uniform() < static_cast<double>(options_.max_rate * s[k]) / 1000.0)
          out.push_back({snn::aer_address(options_.module, static_cast<std::uint32_t>(k)),
                         static_cast<std::uint32_t>(static_cast<std::uint64_t>(now_us + t * 1000))});
    events = out.size();
    if (probing()) {
      float rates[os::Payload::kInlineValues];
      for (std::size_t k = 0; k < x.size(); ++k) rates[k] = options_.max_rate * s[k];
      probe("rates", std::span<const float>(rates, x.size()));
    }
    send(0, snn::aer_payload(std::move(out)));
  }
  counters_.inputs.bump();
  counters_.sent.bump();
  counters_.events.bump(events);
}

kernel::Status SpikeEncoderTask::on_parameter_changed(std::string_view /*name*/) {
  auto checked = create(options_);
  if (!checked) return Error{checked.error()};
  return {};
}

// ---- decoder ----

kernel::Result<std::unique_ptr<SpikeDecoderTask>> SpikeDecoderTask::create(SpikeDecoderOptions options) {
  if (options.channels < 1 || options.channels > kMaxChannels)
    return Error{"channels must be 1.." + std::to_string(kMaxChannels)};
  if (!std::isfinite(options.gain) || !std::isfinite(options.offset)) return Error{"gain and offset must be finite"};
  if (!std::isfinite(options.speed_limit) || options.speed_limit <= 0)
    return Error{"speed_limit must be a positive number"};
  if (options.window < 1ms || options.window > 60s) return Error{"window must be 1ms..60s"};
  auto task = std::unique_ptr<SpikeDecoderTask>(new SpikeDecoderTask(options));
  task->rates_.assign(options.channels, 0.0f);
  return task;
}

SpikeCodingStats SpikeDecoderTask::stats() const { return counters_.snapshot(); }

std::vector<float> SpikeDecoderTask::rates() const {
  std::lock_guard lock(mu_);
  return rates_;
}

void SpikeDecoderTask::ignore(const std::string& why) {
  counters_.ignored.bump();
  warn_ignored(warning_, now(), options_.warn_interval, why, [this](os::LogLevel l, std::string_view t) { log(l, t); });
}

void SpikeDecoderTask::on_message(const os::Message& m) {
  const snn::AerPacket* packet = snn::aer_of(m);
  if (packet == nullptr) {
    ignore("not an AER packet (output-channel spikes expected)");
    return;
  }
  const std::int64_t now_us = now().count() / 1000;
  std::uint64_t counted = 0;
  for (const snn::AerEvent& e : packet->events) {
    const std::uint32_t channel = snn::aer_neuron(e.address);
    if (channel >= options_.channels) continue;
    recent_.push_back({snn::unwrap_us(e.timestamp_us, now_us), channel});
    ++counted;
  }
  while (recent_.size() > kMaxWindowEvents) recent_.pop_front();
  counters_.inputs.bump();
  counters_.events.bump(counted);
}

void SpikeDecoderTask::on_tick() {
  const std::int64_t now_us = now().count() / 1000;
  const std::int64_t window_us = options_.window.count() / 1000;
  // Events arrive in time order per sender; drop the ones that left the window.
  while (!recent_.empty() && recent_.front().at_us <= now_us - window_us) recent_.pop_front();
  std::vector<std::uint32_t> counts(options_.channels, 0);
  for (const Counted& c : recent_)
    if (c.at_us > now_us - window_us && c.at_us <= now_us) ++counts[c.channel];
  float out[kMaxChannels];
  std::vector<float> rates(options_.channels);
  std::uint64_t clamped = 0;
  for (std::size_t c = 0; c < options_.channels; ++c) {
    rates[c] = static_cast<float>(static_cast<double>(counts[c]) * 1e6 / static_cast<double>(window_us));
    double v = options_.offset + options_.gain * rates[c];
    if (!std::isfinite(v)) {
      v = 0;
      ++clamped;
    } else if (std::fabs(v) > options_.speed_limit) {
      v = std::clamp(v, -options_.speed_limit, options_.speed_limit);
      ++clamped;
    }
    out[c] = static_cast<float>(v);
  }
  if (probing()) probe("rates", rates);
  send(0, std::span<const float>(out, options_.channels));
  counters_.sent.bump();
  counters_.clamped.bump(clamped);
  std::lock_guard lock(mu_);
  rates_ = std::move(rates);
}

kernel::Status SpikeDecoderTask::on_parameter_changed(std::string_view /*name*/) {
  auto checked = create(options_);
  if (!checked) return Error{checked.error()};
  return {};
}

}  // namespace symb::control

namespace symb::control {

SpikeCodingStats AerCodecTask::stats() const { return counters_.snapshot(); }

void AerCodecTask::ignore(const std::string& why) {
  counters_.ignored.bump();
  warn_ignored(warning_, now(), warn_interval_, why, [this](os::LogLevel l, std::string_view t) { log(l, t); });
}

void AerCodecTask::on_message(const os::Message& m) {
  if (const snn::AerPacket* packet = snn::aer_of(m)) {
    const std::vector<std::byte> wire = snn::encode_aer(packet->events);
    send(kAerBytesPort, io::bytes_payload(wire));
    counters_.inputs.bump();
    counters_.sent.bump();
    counters_.events.bump(packet->events.size());
    return;
  }
  if (const io::Bytes* bytes = io::bytes_of(m)) {
    auto events = snn::decode_aer(bytes->data);
    if (!events) {
      ignore("bytes that are no AER packet: " + events.error());
      return;
    }
    const std::size_t n = events->size();
    send(kAerPacketsPort, snn::aer_payload(std::move(events).value()));
    counters_.inputs.bump();
    counters_.sent.bump();
    counters_.events.bump(n);
    return;
  }
  ignore("neither an AER packet nor bytes");
}

}  // namespace symb::control
