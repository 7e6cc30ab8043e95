// Time in Symbricator: every clock counts nanoseconds from its own epoch (the start of the
// executor that owns it). One integer type for instants and spans keeps virtual-time arithmetic
// exact, so two runs with the same seed produce bit-identical timestamps.
#pragma once

#include <chrono>
#include <cstdint>

namespace symb::kernel {

using Duration = std::chrono::nanoseconds;
// An instant, measured from the owning clock's epoch.
using Time = std::chrono::nanoseconds;

inline constexpr Time kTimeNever = Time::max();

inline double to_seconds(Duration d) { return static_cast<double>(d.count()) * 1e-9; }
// Whole milliseconds (truncated), for messages.
inline std::int64_t to_milliseconds(Duration d) {
  return std::chrono::duration_cast<std::chrono::milliseconds>(d).count();
}

}  // namespace symb::kernel
