// The hardware-in-the-loop commands (paper V-A; docs/hil.md):
//   symb link   two pseudo-terminal pairs per board (data line, shell line), relayed, at stable
//               paths; optional fault injection on the data line
//   symb sim    the simulator side: a scenario's world at wall-clock pace, one serial line per
//               robot; writes what `symb run` writes, plus link statistics
//   symb board  the board side: one robot's task graph on OS threads, its device tasks on the
//               serial line, its command shell on a second line
// Command-line handling and the loops around the sim layer's HilSimulator and BoardLink.
#pragma once

#include <span>
#include <string_view>

#include "symb/apps/cli_args.hpp"

namespace symb::apps::hil {

// `args` follows the command's name. Each returns the process exit code.
int run_link_command(std::span<const std::string_view> args, const CliContext& ctx);
int run_sim_command(std::span<const std::string_view> args, const CliContext& ctx);
int run_board_command(std::span<const std::string_view> args, const CliContext& ctx);

}  // namespace symb::apps::hil
