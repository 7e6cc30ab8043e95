// `symb run SCENARIO [options]`: the main job. Runs a scenario file in-process and tells where the
// results are. Command-line handling only; the run itself is run_scenario (scenario_run.hpp).
#pragma once

#include <span>
#include <string_view>

#include "symb/apps/cli_args.hpp"

namespace symb::apps::run {

// `args` follows "run". Returns the process exit code.
int run_run_command(std::span<const std::string_view> args, const CliContext& ctx);

}  // namespace symb::apps::run
