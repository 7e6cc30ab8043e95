// The `symb` command line: the top level (help, version) and the dispatch to commands (demo,
// and later run, board, sim, shell, bench). It takes the arguments and the streams from its
// caller, so a test could drive it without a process; main() only supplies argv and the terminal.
#pragma once

#include <span>
#include <string_view>

#include "symb/apps/cli_args.hpp"

namespace symb::apps {

// `args` excludes the program name. Returns the process exit code (kExit*).
int run_symb(std::span<const std::string_view> args, const CliContext& ctx);

// "0.1.0".
std::string_view symb_version();

}  // namespace symb::apps
