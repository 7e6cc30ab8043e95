// `symb serve --node NAME [options]`: one node in a process of its own that joins nodes of other
// processes over the DDS bus (io/dds/dds_bus.hpp). Its tasks are made by shell lines (--exec,
// the node's own command shell: `create`, `hook`, `set`, ...); its remote hooks are declared by
// every process alike (--hook SENDER>RECEIVER[:PORT]); each process builds the ends it holds.
// Peers find each other by DDS discovery. After --duration it sends what it has (waiting for the
// readers' acknowledgements), waits for its peers' senders to finish, and prints each remote
// hook's books and the bus's counts (docs/bus.md).
#pragma once

#include <span>
#include <string_view>

#include "symb/apps/cli_args.hpp"

namespace symb::apps::serve {

// `args` follows "serve". Returns the process exit code.
int run_serve_command(std::span<const std::string_view> args, const CliContext& ctx);

}  // namespace symb::apps::serve
