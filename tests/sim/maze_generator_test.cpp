#include "symb/sim/maze_generator.hpp"

#include <cmath>
#include <numbers>
#include <queue>
#include <set>
#include <vector>

#include <gtest/gtest.h>

namespace symb::sim {
namespace {

// Reads a maze back from its walls alone: which cell borders are blocked. h[row][col] is the
// border at y = row * size under cell (col, row); v[row][col] the border at x = col * size left
// of it. Fails the test on a wall that is not on the grid.
struct Grid {
  std::size_t k;
  std::vector<std::vector<int>> h, v;  // how many walls cover each border unit
};

Grid read_back(const Maze& m) {
  const std::size_t k = m.cells;
  const double s = m.cell_size;
  Grid g{k, std::vector<std::vector<int>>(k + 1, std::vector<int>(k + 1, 0)),
         std::vector<std::vector<int>>(k + 1, std::vector<int>(k + 1, 0))};
  auto index = [&](double x) {
    const double i = x / s;
    EXPECT_NEAR(i, std::round(i), 1e-9) << "wall end off the grid: " << x;
    return static_cast<std::size_t>(std::llround(i));
  };
  for (const WallSpec& w : m.world.walls) {
    if (w.y1 == w.y2) {
      const std::size_t row = index(w.y1);
      for (std::size_t c = index(std::min(w.x1, w.x2)); c < index(std::max(w.x1, w.x2)); ++c) ++g.h[row][c];
    } else {
      EXPECT_EQ(w.x1, w.x2) << "a wall neither horizontal nor vertical";
      const std::size_t col = index(w.x1);
      for (std::size_t r = index(std::min(w.y1, w.y2)); r < index(std::max(w.y1, w.y2)); ++r) ++g.v[r][col];
    }
  }
  return g;
}

// Cells reachable from cell (0, 0) without crossing a wall.
std::size_t reachable(const Grid& g) {
  const std::size_t k = g.k;
  std::vector<char> seen(k * k, 0);
  std::queue<std::size_t> q;
  q.push(0);
  seen[0] = 1;
  std::size_t n = 0;
  while (!q.empty()) {
    const std::size_t cell = q.front();
    q.pop();
    ++n;
    const std::size_t c = cell % k, r = cell / k;
    auto go = [&](std::size_t to) {
      if (!seen[to]) {
        seen[to] = 1;
        q.push(to);
      }
    };
    if (c > 0 && g.v[r][c] == 0) go(cell - 1);
    if (c + 1 < k && g.v[r][c + 1] == 0) go(cell + 1);
    if (r > 0 && g.h[r][c] == 0) go(cell - k);
    if (r + 1 < k && g.h[r + 1][c] == 0) go(cell + k);
  }
  return n;
}

std::size_t blocked_borders(const Grid& g) {
  std::size_t n = 0;
  for (std::size_t r = 0; r < g.k; ++r)
    for (std::size_t c = 0; c < g.k; ++c) {
      EXPECT_LE(g.h[r][c], 1) << "two walls on one border";
      EXPECT_LE(g.v[r][c], 1) << "two walls on one border";
      n += (g.h[r][c] > 0) + (g.v[r][c] > 0);
    }
  return n;
}

TEST(MazeGenerator, APerfectMazeIsATreeOverAllCells) {
  for (std::uint64_t seed = 1; seed <= 20; ++seed)
    for (bool merge : {false, true}) {
      MazeOptions o;
      o.cells = 7;
      o.loop_fraction = 0;
      o.merge_walls = merge;
      o.seed = seed;
      auto m = generate_maze(o);
      ASSERT_TRUE(m) << m.error();
      const Grid g = read_back(*m);
      EXPECT_EQ(reachable(g), 49u) << "seed " << seed;
      // A spanning tree of K^2 cells opens K^2 - 1 of the 2K(K-1) inner borders.
      EXPECT_EQ(blocked_borders(g), 2u * 7 * 6 - 48) << "seed " << seed;
    }
}

TEST(MazeGenerator, LoopsRemoveTheRequestedShareOfWalls) {
  MazeOptions o;
  o.cells = 10;
  o.loop_fraction = 0.15;
  const Grid g = read_back(*generate_maze(o));
  const std::size_t perfect = 2 * 10 * 9 - 99;  // (K-1)^2 = 81 walls in the perfect maze
  EXPECT_EQ(blocked_borders(g), perfect - 12);  // round(0.15 * 81)
  EXPECT_EQ(reachable(g), 100u);
  o.loop_fraction = 1;
  EXPECT_TRUE(generate_maze(o)->world.walls.empty());
}

TEST(MazeGenerator, MergingMakesFewerWallsOfTheSameShape) {
  MazeOptions o;
  o.cells = 12;
  o.merge_walls = false;
  const Maze separate = *generate_maze(o);
  o.merge_walls = true;
  const Maze merged = *generate_maze(o);
  EXPECT_LT(merged.world.walls.size(), separate.world.walls.size());
  const Grid a = read_back(separate), b = read_back(merged);
  EXPECT_EQ(a.h, b.h);
  EXPECT_EQ(a.v, b.v);
}

TEST(MazeGenerator, TheSameSeedGivesTheSameMazeAndAnotherSeedAnother) {
  MazeOptions o;
  o.cells = 8;
  o.seed = 99;
  const Maze a = *generate_maze(o), b = *generate_maze(o);
  o.seed = 100;
  const Maze c = *generate_maze(o);
  const Grid ga = read_back(a), gb = read_back(b), gc = read_back(c);
  EXPECT_EQ(ga.h, gb.h);
  EXPECT_EQ(ga.v, gb.v);
  EXPECT_TRUE(ga.h != gc.h || ga.v != gc.v);
}

TEST(MazeGenerator, WallsAndCellsLieInsideTheArena) {
  MazeOptions o;
  o.cells = 6;
  o.cell_size = 40;
  o.wall_thickness = 3;
  o.wall_height = 7;
  const Maze m = *generate_maze(o);
  EXPECT_EQ(m.world.width, 240.0);
  EXPECT_EQ(m.world.height, 240.0);
  EXPECT_EQ(m.world.wall_height, 7.0);
  ASSERT_FALSE(m.world.walls.empty());
  for (const WallSpec& w : m.world.walls) {
    for (double v : {w.x1, w.x2, w.y1, w.y2}) {
      EXPECT_GE(v, 0.0);
      EXPECT_LE(v, 240.0);
    }
    EXPECT_EQ(w.thickness, 3.0);
    EXPECT_GT(std::hypot(w.x2 - w.x1, w.y2 - w.y1), 0.0);
    // Walls on the arena's sides would be redundant: the sides are walled anyway.
    if (w.y1 == w.y2) {
      EXPECT_TRUE(w.y1 > 0 && w.y1 < 240);
    } else {
      EXPECT_TRUE(w.x1 > 0 && w.x1 < 240);
    }
  }
  ASSERT_EQ(m.centres.size(), 36u);
  EXPECT_EQ(m.centres[0].x, 20.0);
  EXPECT_EQ(m.centres[0].y, 20.0);
  EXPECT_EQ(m.centres[7].x, 60.0);  // (col 1, row 1)
  EXPECT_EQ(m.centres[7].y, 60.0);
}

TEST(MazeGenerator, RandomStartsAreDistinctCellsWithRandomHeadings) {
  MazeOptions o;
  o.cells = 5;
  const Maze m = *generate_maze(o);
  kernel::RandomStream r1(3), r2(3);
  auto a = m.random_starts(25, r1);
  auto b = m.random_starts(25, r2);
  ASSERT_TRUE(a);
  ASSERT_EQ(a->size(), 25u);
  std::set<std::pair<double, double>> cells;
  std::set<double> headings;
  for (std::size_t i = 0; i < a->size(); ++i) {
    const Pose& p = (*a)[i];
    cells.insert({p.x, p.y});
    headings.insert(p.theta);
    EXPECT_GE(p.theta, -std::numbers::pi);
    EXPECT_LT(p.theta, std::numbers::pi);
    EXPECT_EQ(p.x, (*b)[i].x);
    EXPECT_EQ(p.theta, (*b)[i].theta);
  }
  EXPECT_EQ(cells.size(), 25u);
  EXPECT_GT(headings.size(), 20u);
  auto too_many = m.random_starts(26, r1);
  ASSERT_FALSE(too_many);
  EXPECT_NE(too_many.error().find("26"), std::string::npos);
}

TEST(MazeGenerator, BadOptionsAreRejectedByName) {
  auto error_of = [](MazeOptions o) {
    auto m = generate_maze(o);
    return m ? std::string() : m.error();
  };
  MazeOptions o;
  o.cells = 0;
  EXPECT_NE(error_of(o).find("cells"), std::string::npos);
  o = {};
  o.cell_size = -1;
  EXPECT_NE(error_of(o).find("cell_size"), std::string::npos);
  o = {};
  o.loop_fraction = std::nan("");
  EXPECT_NE(error_of(o).find("loop_fraction"), std::string::npos);
  o = {};
  o.wall_thickness = 50;
  EXPECT_NE(error_of(o).find("wall_thickness"), std::string::npos);
  o = {};
  o.wall_height = 0;
  EXPECT_NE(error_of(o).find("wall_height"), std::string::npos);
  EXPECT_TRUE(generate_maze(MazeOptions{}));
}

TEST(MazeGenerator, GridSizeFollowsTheBenchmarkRule) {
  EXPECT_EQ(maze_cells_for_robots(0), 4u);
  EXPECT_EQ(maze_cells_for_robots(1), 4u);
  EXPECT_EQ(maze_cells_for_robots(8), 4u);
  EXPECT_EQ(maze_cells_for_robots(9), 5u);  // sqrt(18) = 4.24
  EXPECT_EQ(maze_cells_for_robots(100), 15u);
  EXPECT_EQ(maze_cells_for_robots(1000), 45u);
}

}  // namespace
}  // namespace symb::sim
