// Number text: the one place that writes a list of numbers as text ("1 2.5 -3", shortest form that
// reads back exactly) and reads it back, for streams in text mode, device ioctls and logs.
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "symb/kernel/result.hpp"

namespace symb::io {

// Space-separated, each float in its shortest exact text form.
std::string format_numbers(std::span<const float> values);
// Numbers separated by spaces or commas; an error gives the column of the first bad one. NaN and
// infinity text pass through, for the caller to judge.
kernel::Result<std::vector<float>> parse_numbers(std::string_view text);

}  // namespace symb::io
