// The hardware-in-the-loop commands (paper V-A; docs/hil.md):
//   symb link   two pseudo-terminal pairs per board (data line, shell line), relayed, at stable
//               paths; optional fault injection on the data line
//   symb sim    the simulator side: a scenario's world at wall-clock pace, one serial line per
//               robot; writes what `symb run` writes, plus link statistics
//   symb board  the board side: one robot's task graph on OS threads, its device tasks on the
//               serial line, its command shell on a second line; with --lockstep its node on
//               a clock the frames drive
// Command-line handling and the loops around the sim layer's HilSimulator, BoardLink and
// HilRobotBoard.
#pragma once

#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "symb/apps/cli_args.hpp"
#include "symb/apps/view/view_request.hpp"
#include "symb/io/dds/dds_frame_stream.hpp"
#include "symb/kernel/time.hpp"
#include "symb/sim/scenario.hpp"

namespace symb::apps::hil {

// `args` follows the command's name. Each returns the process exit code.
int run_link_command(std::span<const std::string_view> args, const CliContext& ctx);
int run_sim_command(std::span<const std::string_view> args, const CliContext& ctx);
int run_board_command(std::span<const std::string_view> args, const CliContext& ctx);

// The 3D forms (hil_organism_commands.cpp): one module of the organism on the board, at the
// other end of a serial line or of a DDS frame stream (--dds: topics rt/<prefix>/<module>/to_robot
// and .../to_world, found by discovery with no configuration).
struct SimOrganismArgs {
  std::vector<std::string> serial;  // exactly one, or none with dds
  std::optional<io::DdsFrameOptions> dds;
  std::string board;  // --board: the module on the board
  std::optional<std::uint64_t> seed;
  kernel::Duration duration{0};
  kernel::Duration hold = std::chrono::milliseconds(300);
  kernel::Duration wait = std::chrono::seconds(60);
  double corrupt = 0;
  bool lockstep = false;  // wait for every answer (up to 1 s) instead of keeping the wall-clock pace
  bool quiet = false;
  std::optional<std::filesystem::path> out_dir;
};
int run_sim_organism(const sim::Scenario& scenario, const SimOrganismArgs& args, const CliContext& ctx);

struct BoardOrganismArgs {
  std::string serial, shell, robot;  // serial: empty with dds
  std::optional<io::DdsFrameOptions> dds;
  std::optional<std::uint64_t> seed;
  std::optional<kernel::Duration> duration;
  kernel::Duration stats_every = std::chrono::seconds(5);
  bool quiet = false;
  view::ViewRequest view;  // --view: the module's task graph, probes, log and shell in a browser
};
int run_board_organism(const sim::Scenario& scenario, const BoardOrganismArgs& args, const CliContext& ctx);

// A Thymio II over the Aseba protocol (aseba_board.cpp; docs/thymio.md): `--robot
// aseba:tcp:HOST:PORT` (Aseba Playground, or a robot behind Aseba's switch) or
// `aseba:serial:PATH` (a Thymio on USB).
struct AsebaTarget {
  std::string host;  // tcp
  std::uint16_t port = 0;
  std::string serial_path;  // serial
};
std::variant<AsebaTarget, UsageError> parse_aseba_target(std::string_view text);
struct BoardAsebaArgs {
  AsebaTarget target;
  std::string shell;
  std::optional<std::uint64_t> seed;
  std::optional<kernel::Duration> duration;
  kernel::Duration stats_every = std::chrono::seconds(5);
  std::optional<double> speed_scale;  // default: 1 over TCP (Playground), 16.6/20 on serial (a real robot)
  bool quiet = false;
  view::ViewRequest view;  // --view: the robot's task graph, probes, log and shell in a browser
};
// Runs the scenario's first robot on the Thymio until Ctrl-C or the duration.
int run_board_aseba(const sim::Scenario& scenario, const BoardAsebaArgs& args, const CliContext& ctx);
// Writes the scenario's world as an Aseba Playground world file, its robots from port `port` on.
int write_playground(const sim::Scenario& scenario, const std::string& out, std::uint16_t port, const CliContext& ctx);

}  // namespace symb::apps::hil
