#include "symb/io/number_text.hpp"

#include <charconv>

namespace symb::io {

std::string format_numbers(std::span<const float> values) {
  std::string text;
  char buf[32];
  for (float x : values) {
    if (!text.empty()) text.push_back(' ');
    auto r = std::to_chars(buf, buf + sizeof buf, x);
    text.append(buf, r.ptr);
  }
  return text;
}

kernel::Result<std::vector<float>> parse_numbers(std::string_view text) {
  std::vector<float> v;
  std::size_t pos = 0;
  while (pos < text.size()) {
    if (text[pos] == ' ' || text[pos] == ',') {
      ++pos;
      continue;
    }
    float x = 0;
    auto [ptr, ec] = std::from_chars(text.data() + pos, text.data() + text.size(), x);
    if (ec != std::errc{} || ptr == text.data() + pos)
      return kernel::Error{"column " + std::to_string(pos + 1) + ": expected a number"};
    v.push_back(x);
    pos = static_cast<std::size_t>(ptr - text.data());
  }
  return v;
}

}  // namespace symb::io
