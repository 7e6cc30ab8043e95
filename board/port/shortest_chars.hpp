// The shortest text that reads back as the same double or float, in std::to_chars's plain format
// (fixed or scientific, whichever is shorter, fixed on a tie): what std::to_chars(first, last, v)
// writes. The board supplies std::to_chars with it (board/port/to_chars.cpp) because libstdc++'s
// own pulls in 130 KB of Ryu tables, half the board's flash. It finds the digits with printf's
// correctly rounded %.*e and the fewest digits that read back (strtod/strtof): the closest
// shortest decimal, which is the one Ryu gives. Header-only so the host tests compare it with
// libstdc++ on many values (tests/kernel/board_port_test.cpp).
#pragma once

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace symb::board {

template <class T>
std::to_chars_result shortest_chars(char* first, char* last, T value) {
  char out[64];
  std::size_t n = 0;
  if (std::signbit(value)) out[n++] = '-';
  if (std::isnan(value)) {
    std::memcpy(out + n, "nan", 3);
    n += 3;
  } else if (std::isinf(value)) {
    std::memcpy(out + n, "inf", 3);
    n += 3;
  } else if (value == 0) {
    out[n++] = '0';
  } else {
    const double a = std::fabs(static_cast<double>(value));
    constexpr int kMaxDigits = sizeof(T) == 4 ? 9 : 17;
    char sci[48];
    for (int p = 0; p < kMaxDigits; ++p) {
      std::snprintf(sci, sizeof sci, "%.*e", p, a);
      const bool same =
          sizeof(T) == 4 ? std::strtof(sci, nullptr) == static_cast<float>(a) : std::strtod(sci, nullptr) == a;
      if (same) break;
    }
    // sci is d[.ddd]e[+-]X...: its digits and exponent.
    char digits[24];
    int nd = 0;
    const char* s = sci;
    for (; *s != 'e'; ++s)
      if (*s != '.') digits[nd++] = *s;
    const int exponent = std::atoi(s + 1);
    char fixed[400];
    int nf = 0;
    if (exponent >= nd - 1) {
      // An integer: libstdc++ writes its exact digits here, not the shortest ones padded with
      // zeros (413242816.0f is "413242816", not "413242800"); the same length either way.
      nf = std::snprintf(fixed, sizeof fixed, "%.0f", a);
    } else if (exponent >= 0) {
      for (int i = 0; i < nd; ++i) {
        if (i == exponent + 1) fixed[nf++] = '.';
        fixed[nf++] = digits[i];
      }
    } else {
      fixed[nf++] = '0';
      fixed[nf++] = '.';
      for (int i = 0; i < -exponent - 1; ++i) fixed[nf++] = '0';
      for (int i = 0; i < nd; ++i) fixed[nf++] = digits[i];
    }
    char scientific[40];
    int ns = 0;
    scientific[ns++] = digits[0];
    if (nd > 1) {
      scientific[ns++] = '.';
      for (int i = 1; i < nd; ++i) scientific[ns++] = digits[i];
    }
    ns += std::snprintf(scientific + ns, sizeof scientific - static_cast<std::size_t>(ns), "e%c%02d",
                        exponent < 0 ? '-' : '+', exponent < 0 ? -exponent : exponent);
    if (nf <= ns) {
      std::memcpy(out + n, fixed, static_cast<std::size_t>(nf));
      n += static_cast<std::size_t>(nf);
    } else {
      std::memcpy(out + n, scientific, static_cast<std::size_t>(ns));
      n += static_cast<std::size_t>(ns);
    }
  }
  if (static_cast<std::size_t>(last - first) < n) return {last, std::errc::value_too_large};
  std::memcpy(first, out, n);
  return {first + n, std::errc{}};
}

}  // namespace symb::board
