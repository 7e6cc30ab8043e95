// `symb serve --node NAME [options]`: one node in a process of its own that joins nodes of other
// processes over the DDS bus (io/dds/dds_bus.hpp). Its tasks are made by shell lines (--exec,
// the node's own command shell: `create`, `hook`, `set`, ...); its remote hooks are declared by
// every process alike (--hook SENDER>RECEIVER[:PORT]); each process builds the ends it holds.
// Peers find each other by DDS discovery. After --duration it sends what it has (waiting for the
// readers' acknowledgements), waits for its peers' senders to finish, and prints each remote
// hook's books and the bus's counts (docs/bus.md).
//
// `symb serve --scenario S --robot NAME [options]`: one robot of a split world (serve_robot.cpp):
// the robot's node, built from the scenario as `symb run` builds it, answers the world of a
// `symb run S --bus dds --remote NAME` over DDS in lockstep (sim/hil_split_robot.hpp).
#pragma once

#include <chrono>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "symb/apps/cli_args.hpp"
#include "symb/io/dds/dds_frame_stream.hpp"

namespace symb::apps::serve {

// `args` follows "serve". Returns the process exit code.
int run_serve_command(std::span<const std::string_view> args, const CliContext& ctx);

struct ServeRobotArgs {
  std::string scenario, robot;
  io::DdsFrameOptions dds;
  kernel::Duration wait = std::chrono::seconds(60);  // for the world's hello
  std::vector<std::string> plugins;
};
// The robot of a split world: until the world ends the run (exit 0), is lost, never comes or
// refuses (exit 1).
int run_serve_robot(const ServeRobotArgs& args, const CliContext& ctx);

}  // namespace symb::apps::serve
