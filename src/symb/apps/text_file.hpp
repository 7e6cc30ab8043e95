// A whole file read or written at once, as the commands' result files are: errors name the path
// and are values (kernel::Status), never exceptions.
#pragma once

#include <filesystem>
#include <string>

#include "symb/kernel/result.hpp"

namespace symb::apps {

kernel::Result<std::string> read_file(const std::filesystem::path& path);
// Creates or truncates `path`; a write that did not reach the file (full disk, no folder) is an error.
kernel::Status write_file(const std::filesystem::path& path, const std::string& text);

}  // namespace symb::apps
