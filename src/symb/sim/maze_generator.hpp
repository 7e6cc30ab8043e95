// Maze generator: a seeded maze on a K x K grid of square cells, as plain data (a WorldSpec) for
// any backend. A perfect maze is carved by a randomized depth-first search (every cell reachable
// by exactly one path), then a fraction of the walls left inside is knocked out so that the maze
// has loops and a wall-follower is not the only way through. This is the reference benchmark's
// design (simulators.md 2.2: 50 cm cells, about 15 % of the walls removed, K = max(4,
// ceil(sqrt(2 N))) for N robots so there are two cells per robot); the swarm scenarios use it too.
//
// The arena is exactly K * cell_size square; its four sides are the WorldSpec's implicit walls,
// so spec.walls holds inner walls only, each on a cell border. Every cell is free space, and a
// robot (Thymio2: 8 cm bounding radius) fits at a cell centre when cell_size - thickness > 16.
// Same options (seed included), same maze, on any machine: the generator draws only from a
// kernel::RandomStream.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/result.hpp"
#include "symb/sim/world_spec.hpp"

namespace symb::sim {

struct MazeOptions {
  std::size_t cells = 4;        // K, 1..1000
  double cell_size = 50.0;      // cm
  double loop_fraction = 0.15;  // share of the perfect maze's inner walls removed, 0..1
  double wall_thickness = 2.0;  // cm, > 0 and below cell_size
  double wall_height = 10.0;    // cm
  bool merge_walls = true;      // one wall per straight run of borders, not one per border:
                                // the same geometry with fewer objects (Enki is O(objects^2))
  std::uint64_t seed = 1;
};

struct Maze {
  WorldSpec world;
  std::size_t cells = 0;  // K
  double cell_size = 0;
  // Cell centres, row by row from the bottom left: cell (col, row) is centres[row * K + col].
  std::vector<Pose> centres;

  // Start poses for `count` robots: distinct random cells, each at its centre with a random
  // heading (the reference benchmark's placement). Deterministic for a given stream state. Fails
  // when count exceeds the number of cells.
  kernel::Result<std::vector<Pose>> random_starts(std::size_t count, kernel::RandomStream& random) const;
};

// Checks the options (errors name the option) and builds the maze.
kernel::Result<Maze> generate_maze(const MazeOptions& options);

// The reference benchmark's grid size for `robots` robots: max(4, ceil(sqrt(2 * robots))).
std::size_t maze_cells_for_robots(std::size_t robots);

}  // namespace symb::sim
