// std::from_chars for double and float (chars_format general, fixed, scientific) with newlib's
// strtod/strtof: what the board supplies (board/port/to_chars.cpp) so that libstdc++'s
// fast_float (20 KB of flash) stays out. The pattern is from_chars's own, checked here before
// strtod sees the text: an optional '-', digits with an optional '.', an exponent as the format
// allows, or inf/infinity/nan/nan(...) in any case; no leading space and no '+'. A value too
// large or too small for the type (rounding to infinity or to zero) is result_out_of_range and
// leaves `value` alone. Hex is refused (the shared code never asks for it). Header-only so the
// host tests compare it with libstdc++ (tests/kernel/board_port_test.cpp).
#pragma once

#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>

namespace symb::board {

template <class T>
std::from_chars_result parse_chars(const char* first, const char* last, T& value,
                                   std::chars_format fmt = std::chars_format::general) {
  const char* p = first;
  const bool negative = p != last && *p == '-';
  if (negative) ++p;
  auto ieq = [&](const char* at, const char* word) {
    const std::size_t n = std::strlen(word);
    if (static_cast<std::size_t>(last - at) < n) return false;
    for (std::size_t i = 0; i < n; ++i)
      if (std::tolower(static_cast<unsigned char>(at[i])) != word[i]) return false;
    return true;
  };
  if (fmt == std::chars_format::hex) return {first, std::errc::invalid_argument};
  if (ieq(p, "inf")) {
    const char* end = ieq(p, "infinity") ? p + 8 : p + 3;
    value = negative ? -std::numeric_limits<T>::infinity() : std::numeric_limits<T>::infinity();
    return {end, std::errc{}};
  }
  if (ieq(p, "nan")) {
    const char* end = p + 3;
    if (end != last && *end == '(') {
      const char* q = end + 1;
      while (q != last && (std::isalnum(static_cast<unsigned char>(*q)) || *q == '_')) ++q;
      if (q != last && *q == ')') end = q + 1;
    }
    value = negative ? -std::numeric_limits<T>::quiet_NaN() : std::numeric_limits<T>::quiet_NaN();
    return {end, std::errc{}};
  }
  const char* digits_start = p;
  std::size_t mantissa_digits = 0;
  while (p != last && std::isdigit(static_cast<unsigned char>(*p))) ++p, ++mantissa_digits;
  if (p != last && *p == '.') {
    ++p;
    while (p != last && std::isdigit(static_cast<unsigned char>(*p))) ++p, ++mantissa_digits;
  }
  if (mantissa_digits == 0) return {first, std::errc::invalid_argument};
  const bool may_exp = fmt != std::chars_format::fixed;
  const bool must_exp = fmt == std::chars_format::scientific;
  bool has_exp = false;
  if (may_exp && p != last && (*p == 'e' || *p == 'E')) {
    const char* q = p + 1;
    if (q != last && (*q == '+' || *q == '-')) ++q;
    if (q != last && std::isdigit(static_cast<unsigned char>(*q))) {
      while (q != last && std::isdigit(static_cast<unsigned char>(*q))) ++q;
      p = q;
      has_exp = true;
    }
  }
  if (must_exp && !has_exp) return {first, std::errc::invalid_argument};
  // strtod needs a terminated copy; longer texts than this are not numbers the board reads.
  char buf[128];
  const auto n = static_cast<std::size_t>(p - digits_start);
  if (n + 2 > sizeof buf) return {first, std::errc::invalid_argument};
  std::size_t k = 0;
  if (negative) buf[k++] = '-';
  std::memcpy(buf + k, digits_start, n);
  buf[k + n] = '\0';
  errno = 0;
  const T v = sizeof(T) == 4 ? static_cast<T>(std::strtof(buf, nullptr)) : static_cast<T>(std::strtod(buf, nullptr));
  if (errno == ERANGE && (std::isinf(v) || v == 0)) return {p, std::errc::result_out_of_range};
  value = v;
  return {p, std::errc{}};
}

}  // namespace symb::board
