// Shared by the fuzz targets of text parsers: whether an error message starts with the location
// "LINE:COLUMN: " that every parser of the project promises.
#pragma once

#include <cctype>
#include <cstddef>
#include <string>

namespace symb::fuzz {

inline bool located(const std::string& e) {
  std::size_t i = 0;
  auto digits = [&] {
    const std::size_t s = i;
    while (i < e.size() && std::isdigit(static_cast<unsigned char>(e[i]))) ++i;
    return i > s;
  };
  if (!digits() || i >= e.size() || e[i++] != ':') return false;
  if (!digits() || i + 1 >= e.size()) return false;
  return e[i] == ':' && e[i + 1] == ' ';
}

}  // namespace symb::fuzz
