#include "symb/robot/channel_spec.hpp"

#include <algorithm>
#include <charconv>
#include <cstdio>

#include "symb/os/message.hpp"
#include "symb/os/param.hpp"

namespace symb::robot {

using kernel::Error;

std::string describe(const ChannelSpec& c) {
  char range[64];
  std::snprintf(range, sizeof range, " [%g, %g] ", static_cast<double>(c.min), static_cast<double>(c.max));
  return c.name + range + (c.units.empty() ? std::string("-") : c.units);
}

kernel::Status validate_channels(std::span<const ChannelSpec> channels) {
  if (channels.empty()) return Error{"a device needs at least one channel"};
  if (channels.size() > os::Payload::kInlineValues)
    return Error{"a device has at most " + std::to_string(os::Payload::kInlineValues) + " channels, not " +
                 std::to_string(channels.size())};
  for (std::size_t i = 0; i < channels.size(); ++i) {
    const ChannelSpec& c = channels[i];
    const std::string which = "channel " + std::to_string(i) + " '" + c.name.substr(0, 63) + "'";
    if (!os::is_valid_name(c.name)) return Error{which + ": invalid name"};
    if (!std::isfinite(c.min) || !std::isfinite(c.max)) return Error{which + ": bounds must be finite"};
    if (c.min > c.max) return Error{which + ": min is above max"};
    for (std::size_t j = 0; j < i; ++j)
      if (channels[j].name == c.name) return Error{which + ": name used twice"};
  }
  return {};
}

const char* to_string(SampleFault f) {
  switch (f) {
    case SampleFault::kNone: return "none";
    case SampleFault::kWrongCount: return "wrong number of values";
    case SampleFault::kNotANumber: return "NaN value";
  }
  return "?";
}

namespace {

template <class Channel>
Conditioned condition(std::span<const Channel> channels, std::span<const float> in, std::span<float> out) {
  Conditioned r;
  if (in.size() != channels.size() || out.size() < channels.size()) {
    r.fault = SampleFault::kWrongCount;
    return r;
  }
  // Checked before anything is written, so a refused sample leaves `out` untouched.
  for (std::size_t i = 0; i < in.size(); ++i) {
    if (std::isnan(in[i])) {
      r.fault = SampleFault::kNotANumber;
      r.channel = i;
      return r;
    }
  }
  // NaN is out by now, so the bounds apply as a plain max and min (no NaN test per value, and no
  // branch per bound: every robot's every reading and command comes through here).
  for (std::size_t i = 0; i < in.size(); ++i) {
    const float v = std::min(std::max(in[i], channels[i].min), channels[i].max);
    r.clamped += v != in[i] ? 1 : 0;
    out[i] = v;
  }
  return r;
}

}  // namespace

Conditioned condition_sample(std::span<const ChannelSpec> channels, std::span<const float> in, std::span<float> out) {
  return condition(channels, in, out);
}

Conditioned condition_sample(std::span<const ChannelRange> ranges, std::span<const float> in, std::span<float> out) {
  return condition(ranges, in, out);
}

std::vector<ChannelRange> ranges_of(std::span<const ChannelSpec> channels) {
  std::vector<ChannelRange> r;
  r.reserve(channels.size());
  for (const ChannelSpec& c : channels) r.push_back({c.min, c.max});
  return r;
}

namespace {

// Reads a finite float starting at text[pos] and moves pos past it.
kernel::Result<float> read_number(std::string_view text, std::size_t& pos, const char* what) {
  const std::size_t start = pos;
  float v = 0;
  const char* first = text.data() + pos;
  const char* last = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(first, last, v);
  if (ec != std::errc{} || ptr == first || !std::isfinite(v))
    return Error{"column " + std::to_string(start + 1) + ": expected a finite number for " + what};
  pos += static_cast<std::size_t>(ptr - first);
  return v;
}

}  // namespace

kernel::Result<std::vector<ChannelSpec>> apply_ranges(std::span<const ChannelSpec> base, std::string_view text) {
  std::vector<ChannelSpec> out(base.begin(), base.end());
  if (text.empty()) return out;
  struct Range {
    float lo, hi;
  };
  std::vector<Range> ranges;
  std::size_t pos = 0;
  for (;;) {
    const std::size_t column = pos + 1;
    auto lo = read_number(text, pos, "a lower bound");
    if (!lo) return Error{lo.error()};
    if (pos >= text.size() || text[pos] != ':')
      return Error{"column " + std::to_string(pos + 1) + ": expected ':' between the bounds (lo:hi)"};
    ++pos;
    auto hi = read_number(text, pos, "an upper bound");
    if (!hi) return Error{hi.error()};
    if (*lo > *hi) return Error{"column " + std::to_string(column) + ": lower bound above upper bound"};
    ranges.push_back({*lo, *hi});
    if (pos == text.size()) break;
    if (text[pos] != ',') return Error{"column " + std::to_string(pos + 1) + ": expected ',' between ranges"};
    ++pos;
  }
  if (ranges.size() == 1) {
    for (auto& c : out) c.min = ranges[0].lo, c.max = ranges[0].hi;
    return out;
  }
  if (ranges.size() != out.size())
    return Error{std::to_string(ranges.size()) + " ranges for " + std::to_string(out.size()) +
                 " channels: give one range for all, or one per channel"};
  for (std::size_t i = 0; i < out.size(); ++i) out[i].min = ranges[i].lo, out[i].max = ranges[i].hi;
  return out;
}

}  // namespace symb::robot
