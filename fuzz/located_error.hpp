// Shared by the fuzz targets of text parsers: whether an error message starts with the location
// "LINE:COLUMN: " that every parser of the project promises.
#pragma once

#include <string>

#include "symb/kernel/source_text.hpp"

namespace symb::fuzz {

inline bool located(const std::string& e) { return kernel::split_location(e).at.has_value(); }

}  // namespace symb::fuzz
