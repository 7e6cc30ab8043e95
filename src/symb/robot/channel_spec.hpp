// ChannelSpec: one number a sensor measures or an actuator takes (a distance, a wheel speed, an
// LED's brightness): its name, its units and the range its values may take. The range is a fact
// of the hardware (an ADC reads 0..1023, a wheel turns at most 0.3 m/s), so every value that
// crosses the robot layer is conditioned against it here, once, the same way everywhere:
//  - NaN carries no information: the whole sample (or command) is rejected, never half applied;
//  - anything else outside [min, max], infinities included, is clamped to the nearer bound: a
//    saturated reading or an over-eager command still means "as far as it goes".
// Callers count what was clamped and rejected and log it at a limited rate (WarningLimiter).
//
// A sample is at most os::Payload::kInlineValues channels, so it always travels inside a message
// without touching the heap.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "symb/kernel/result.hpp"

namespace symb::robot {

// A channel's range alone, which is all that conditioning reads. Devices keep their channels'
// ranges packed in one array: in a ChannelSpec the two strings put every range on a cache line of
// its own, and a swarm conditions a reading of each of its thousands of robots every step.
struct ChannelRange {
  float min = 0.0f;
  float max = 0.0f;

  float clamp(float v) const {
    if (std::isnan(v)) return v;
    return v < min ? min : (v > max ? max : v);
  }
};

struct ChannelSpec {
  std::string name;   // a valid os name: "ir0", "left"
  std::string units;  // "m", "rad/s", "raw", ...
  float min = 0.0f;
  float max = 0.0f;

  bool contains(float v) const { return v >= min && v <= max; }
  // The nearest value in range; NaN stays NaN (callers reject it).
  float clamp(float v) const { return ChannelRange{min, max}.clamp(v); }
};

std::vector<ChannelRange> ranges_of(std::span<const ChannelSpec> channels);

// "name [min, max] units", for listings and ioctl answers.
std::string describe(const ChannelSpec& c);

// Checks a channel list: 1 to os::Payload::kInlineValues channels, valid and distinct names,
// finite bounds with min <= max. The error names the channel.
kernel::Status validate_channels(std::span<const ChannelSpec> channels);

// Why a sample was refused as a whole.
enum class SampleFault : std::uint8_t {
  kNone,
  kWrongCount,  // not one value per channel
  kNotANumber,  // a NaN in some channel
};

const char* to_string(SampleFault f);

struct Conditioned {
  std::size_t clamped = 0;  // values moved into range
  SampleFault fault = SampleFault::kNone;
  std::size_t channel = 0;  // kNotANumber: the first channel that held one

  bool ok() const { return fault == SampleFault::kNone; }
};

// Conditions `in` against `channels` into `out` (which needs room for channels.size() values).
// On a fault `out` is left as it was, so a caller can keep its previous output.
Conditioned condition_sample(std::span<const ChannelSpec> channels, std::span<const float> in, std::span<float> out);
Conditioned condition_sample(std::span<const ChannelRange> ranges, std::span<const float> in, std::span<float> out);

// Applies a range override written as text to a copy of `base`: "" keeps base; "lo:hi" gives every
// channel that range; "lo:hi,lo:hi,..." gives one range per channel (exactly one per channel).
// This is how a task created by name narrows a device's ranges (e.g. an LED kept below half
// brightness). Errors give the 1-based column.
kernel::Result<std::vector<ChannelSpec>> apply_ranges(std::span<const ChannelSpec> base, std::string_view text);

}  // namespace symb::robot
