// std::to_chars and std::from_chars for double and float on the board: see shortest_chars.hpp and
// parse_chars.hpp for why. Defined here,
// the linker takes these and never pulls libstdc++'s floating_to_chars.o (and its tables).
#include "port/shortest_chars.hpp"

namespace std {
to_chars_result to_chars(char* first, char* last, double value) {
  return symb::board::shortest_chars(first, last, value);
}
to_chars_result to_chars(char* first, char* last, float value) {
  return symb::board::shortest_chars(first, last, value);
}
}  // namespace std

#include "port/parse_chars.hpp"

namespace std {
from_chars_result from_chars(const char* first, const char* last, double& value, chars_format fmt) {
  return symb::board::parse_chars(first, last, value, fmt);
}
from_chars_result from_chars(const char* first, const char* last, float& value, chars_format fmt) {
  return symb::board::parse_chars(first, last, value, fmt);
}
}  // namespace std
