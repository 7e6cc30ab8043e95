#include "app/maze_graph.hpp"

#include <string>
#include <vector>

#include "symb/control/control_task_types.hpp"
#include "symb/control/mdl2e/mdl2e_task_types.hpp"

namespace symb::board {

namespace {
constexpr std::string_view kMazeProgram = "mdl2e/obstacle_avoidance.mdl2e";
}

std::uint64_t maze_node_seed(std::uint64_t seed, std::size_t index) {
  std::uint64_t z = seed + 0x9e3779b97f4a7c15ULL * (index + 1);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

kernel::Result<std::unique_ptr<MazeGraph>> build_maze_graph(kernel::Executor& executor, std::uint64_t seed) {
  auto g = std::make_unique<MazeGraph>();
  g->types = std::make_unique<os::TaskTypeRegistry>();
  control::ControlResources resources;
  resources.read_program = [](std::string_view reference) -> kernel::Result<std::string> {
    if (reference == kMazeProgram) return std::string(maze_program_text());
    return kernel::Error{"the board holds no program '" + std::string(reference) + "' (it has " +
                         std::string(kMazeProgram) + ")"};
  };
  // Only the maze's controller type: the AHHS and network types (compiled for the board in
  // symb_board_layers) would add 106 KB of parsers and parameter tables, past the 256 KiB flash.
  if (auto st = control::register_mdl2e_task_types(*g->types, resources); !st) return kernel::Error{st.error()};
  g->node = std::make_unique<os::Node>(executor, os::NodeConfig{"thymio", maze_node_seed(seed, 0), 32, g->types.get()});
  const os::TaskType* mdl2e = g->types->find("mdl2e");
  const std::vector<os::ParamAssignment> params{{"program", std::string(kMazeProgram), 1}};
  auto controller = g->node->create("mdl2e", "controller", params, mdl2e->defaults);
  if (!controller) return kernel::Error{"controller: " + controller.error()};
  return g;
}

kernel::Status attach_maze_link(MazeGraph& graph, std::shared_ptr<io::IOStream> data_port) {
  os::Node& node = *graph.node;
  if (auto st = make_hil_tasks(node, std::move(data_port), graph.stats); !st) return st;
  const auto ir = node.find("ir");
  const auto controller = node.find("controller");
  const auto wheels = node.find("wheels");
  if (auto h = node.hook(*ir, *controller); !h) return kernel::Error{"hook ir -> controller: " + h.error()};
  if (auto h = node.hook(*controller, *wheels); !h) return kernel::Error{"hook controller -> wheels: " + h.error()};
  return {};
}

}  // namespace symb::board
