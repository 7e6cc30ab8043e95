// `symb evolve SCENARIO [options]`: an evolution experiment, headless, with a progress line,
// checkpoints and an output folder. Command-line handling only; the run is run_evolution
// (evolve_run.hpp).
#pragma once

#include <span>
#include <string_view>

#include "symb/apps/cli_args.hpp"

namespace symb::apps::evolve {

// `args` follows "evolve". Returns the process exit code.
int run_evolve_command(std::span<const std::string_view> args, const CliContext& ctx);

}  // namespace symb::apps::evolve
