// `symb demo swarm`: the command-line face of run_swarm(). It reads the options, shows progress
// on stderr, writes the output folder and says where it is.
#pragma once

#include <span>
#include <string_view>

#include "symb/apps/cli_args.hpp"

namespace symb::apps {

// `args` follows "demo swarm". Returns the process exit code.
int run_swarm_command(std::span<const std::string_view> args, const CliContext& ctx);

}  // namespace symb::apps
