// The maze robot's control system on the board, as `symb board scenarios/maze.yaml` builds it
// on Linux (src/symb/sim/robot_system.cpp with the HIL device tasks): a node whose registry holds
// the MDL2e task type; link -> ir -> controller (MDL2e, the scenario's
// obstacle_avoidance program, embedded) -> wheels -> link. The scenario's file is not read on the
// board (no YAML, no files): what it says for the maze is written here and kept equal to
// scenarios/maze.yaml by the HIL comparison test.
#pragma once

#include <memory>
#include <string_view>

#include "symb/kernel/executor.hpp"
#include "symb/os/node.hpp"
#include "symb/os/task_type_registry.hpp"

#include "app/hil_tasks.hpp"

namespace symb::board {

std::string_view maze_program_text();  // generated from scenarios/mdl2e/obstacle_avoidance.mdl2e

// The node seed `symb board` gives robot `index` of a scenario with seed `seed`
// (sim::robot_node_seed, the same formula).
std::uint64_t maze_node_seed(std::uint64_t seed, std::size_t index);

struct MazeGraph {
  std::unique_ptr<os::TaskTypeRegistry> types;
  std::unique_ptr<os::Node> node;
  HilStats stats;
};

// Builds the node and its controller; an error names the part that failed. Compiling the program
// is the start-up's largest use of the heap: done first, what it frees is reused by everything
// made after it (the UARTs, the device tasks, the shell), so the heap's high-water is the larger
// of the two, not their sum.
kernel::Result<std::unique_ptr<MazeGraph>> build_maze_graph(kernel::Executor& executor, std::uint64_t seed);
// Adds link, ir and wheels over `data_port` and hooks ir -> controller -> wheels.
kernel::Status attach_maze_link(MazeGraph& graph, std::shared_ptr<io::IOStream> data_port);

}  // namespace symb::board
