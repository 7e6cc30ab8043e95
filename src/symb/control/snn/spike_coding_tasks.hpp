// The tasks around a spiking network that turn sensor values into its input and its output spikes
// into wheel commands (paper IV-B: the network talks to "sensor" and "actuator" modules over hooks):
//
//   ir --> SpikeEncoderTask --currents, or AER input events--> network --port 1: output spikes--> SpikeDecoderTask -->
//   wheels
//
// SpikeEncoderTask (type spike_encoder), on every sensor vector (port 0), per value x:
//   s = clamp(x * input_scale, 0, 1);
//   coding=current: sends [gain * s per channel] at once (the network holds them: current coding);
//   coding=rate: sends an AER packet with, for every 1 ms of the next `window`, an event for
//     channel k with probability max_rate * s / 1000 (Bernoulli, the task's random stream): a Poisson
//     spike train of rate max_rate * s (rate coding). Event addresses carry `module`.
// SpikeDecoderTask (type spike_decoder), fed output-channel spikes (AER, neuron field = channel):
//   every period sends [offset + gain * rate(c) for c < channels], rate(c) the channel's spikes in
//   the last `window` per second, clamped to +-speed_limit (so a silent network drives at
//   `offset`). Foreign messages are counted and ignored with a rate-limited warning; nothing NaN
//   ever leaves either task.
// AerCodecTask (type aer_codec, at the end of this file) turns packets into bytes and back, for
// spikes that cross a byte link to another node.
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "symb/control/snn/aer.hpp"
#include "symb/kernel/counter.hpp"
#include "symb/kernel/result.hpp"
#include "symb/os/task.hpp"
#include "symb/os/warning_limiter.hpp"

namespace symb::control {

enum class SpikeCoding { kCurrent, kRate };
kernel::Result<SpikeCoding> parse_spike_coding(std::string_view text);

struct SpikeEncoderOptions {
  SpikeCoding coding = SpikeCoding::kCurrent;
  float input_scale = 1.0f / 4505.0f;                       // the Thymio's IR range to 0..1
  float gain = 20;                                          // current at s = 1 (current coding)
  float max_rate = 200;                                     // Hz at s = 1 (rate coding)
  kernel::Duration window = std::chrono::milliseconds(30);  // rate coding: events per reading
  std::uint32_t module = 0;
  kernel::Duration warn_interval = std::chrono::seconds(1);
};

struct SpikeCodingStats {
  std::uint64_t inputs = 0;   // sensor vectors (encoder) or AER packets (decoder) taken
  std::uint64_t events = 0;   // events sent (encoder) or counted (decoder)
  std::uint64_t sent = 0;     // messages sent
  std::uint64_t ignored = 0;  // bad or foreign messages
  std::uint64_t clamped = 0;  // decoder: wheel values cut to the speed limit
};

// The counters behind SpikeCodingStats (kernel/counter.hpp).
struct SpikeCodingCounters {
  kernel::Counter inputs, events, sent, ignored, clamped;
  SpikeCodingStats snapshot() const {
    return {.inputs = inputs.load(),
            .events = events.load(),
            .sent = sent.load(),
            .ignored = ignored.load(),
            .clamped = clamped.load()};
  }
};

class SpikeEncoderTask : public os::Task {
 public:
  static kernel::Result<std::unique_ptr<SpikeEncoderTask>> create(SpikeEncoderOptions options);
  SpikeCodingStats stats() const;

 protected:
  void on_message(const os::Message& m) override;
  kernel::Status on_parameter_changed(std::string_view name) override;

 private:
  explicit SpikeEncoderTask(SpikeEncoderOptions options) : options_(options) { bind_parameters(options_); }
  void ignore(const std::string& why);

  SpikeEncoderOptions options_;
  os::WarningLimiter warning_;
  SpikeCodingCounters counters_;
};

struct SpikeDecoderOptions {
  std::size_t channels = 2;
  double gain = 10;   // wheel units per Hz
  double offset = 0;  // wheel units at 0 Hz
  double speed_limit = 500;
  kernel::Duration window = std::chrono::milliseconds(100);
  kernel::Duration warn_interval = std::chrono::seconds(1);
};

class SpikeDecoderTask : public os::Task {
 public:
  static constexpr std::size_t kMaxChannels = 32;
  static constexpr std::size_t kMaxWindowEvents = 1u << 16;  // older events beyond this are forgotten

  static kernel::Result<std::unique_ptr<SpikeDecoderTask>> create(SpikeDecoderOptions options);
  SpikeCodingStats stats() const;
  // The rates (Hz) of the last command, per channel.
  std::vector<float> rates() const;

 protected:
  void on_message(const os::Message& m) override;
  void on_tick() override;
  kernel::Status on_parameter_changed(std::string_view name) override;

 private:
  explicit SpikeDecoderTask(SpikeDecoderOptions options) : options_(options) { bind_parameters(options_); }
  void ignore(const std::string& why);

  struct Counted {
    std::int64_t at_us;
    std::uint32_t channel;
  };
  SpikeDecoderOptions options_;
  std::deque<Counted> recent_;
  os::WarningLimiter warning_;
  SpikeCodingCounters counters_;
  mutable std::mutex mu_;  // rates_
  std::vector<float> rates_;
};

}  // namespace symb::control

namespace symb::control {

// AerCodecTask (type aer_codec): the bridge between spike packets and bytes, so spikes can leave a
// node over any byte link (a StreamTask in frames mode on a serial line, TCP, CAN) and enter
// another node: an AER packet in -> its wire form (snn::encode_aer) as io::Bytes on port 0
// (kAerBytesPort); io::Bytes in -> decoded -> an AER packet on port 1 (kAerPacketsPort). Bytes
// that do not decode are counted and ignored with a rate-limited warning naming the byte offset.
inline constexpr os::Port kAerBytesPort = 0;
inline constexpr os::Port kAerPacketsPort = 1;

class AerCodecTask : public os::Task {
 public:
  SpikeCodingStats stats() const;

 protected:
  void on_message(const os::Message& m) override;

 private:
  void ignore(const std::string& why);

  kernel::Duration warn_interval_ = std::chrono::seconds(1);
  os::WarningLimiter warning_;
  SpikeCodingCounters counters_;
};

}  // namespace symb::control
