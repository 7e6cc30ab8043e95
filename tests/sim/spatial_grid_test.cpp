// SpatialGrid: every point inside a query and every box overlapping it is visited, once; points
// and queries outside the laid-out area are clamped into the border cells; the cell cap holds.
#include "symb/sim/spatial_grid.hpp"

#include <algorithm>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "symb/kernel/random_stream.hpp"

namespace symb::sim {
namespace spatial_grid_test {

TEST(SpatialGrid, QueriesFindEveryPointInsideOnceInCellThenIndexOrder) {
  kernel::RandomStream rng(11, 1);
  for (int round = 0; round < 30; ++round) {
    std::vector<Pose> points(1 + rng.below(500));
    for (Pose& p : points) p = {rng.uniform(-100, 900), rng.uniform(-50, 400), 0};
    SpatialGrid grid;
    // A layout over only part of where the points are: the rest is clamped into border cells.
    grid.layout({0, 0, 800, 300}, rng.uniform(5, 120), 1 + rng.below(2000));
    grid.set_points(points);
    ASSERT_LE(grid.columns() * grid.rows(), 2000u);
    for (int q = 0; q < 20; ++q) {
      const double x = rng.uniform(-150, 950), y = rng.uniform(-100, 450), r = rng.uniform(0, 200);
      std::vector<std::size_t> visited;
      grid.for_each({x - r, y - r, x + r, y + r}, [&](std::size_t i) { visited.push_back(i); });
      std::vector<std::size_t> sorted = visited;
      std::sort(sorted.begin(), sorted.end());
      ASSERT_EQ(std::adjacent_find(sorted.begin(), sorted.end()), sorted.end()) << "a point twice";
      for (std::size_t i = 0; i < points.size(); ++i) {
        const bool inside =
            points[i].x >= x - r && points[i].x <= x + r && points[i].y >= y - r && points[i].y <= y + r;
        ASSERT_TRUE(!inside || std::binary_search(sorted.begin(), sorted.end(), i)) << "missed point " << i;
      }
      // Fewer candidates than points, when the query is small against the area.
      if (r < 20 && grid.columns() * grid.rows() > 100 && points.size() > 200) {
        EXPECT_LT(visited.size(), points.size() / 2);
      }
    }
  }
}

TEST(SpatialGrid, BoxesAreFoundOnceWhereverTheyOverlapTheQuery) {
  kernel::RandomStream rng(12, 1);
  std::vector<GridBox> boxes(300);
  for (GridBox& b : boxes) {
    const double x = rng.uniform(-50, 1050), y = rng.uniform(-50, 1050);
    b = {x, y, x + rng.uniform(0, 400), y + rng.uniform(0, 30)};
  }
  SpatialGrid grid;
  grid.layout({0, 0, 1000, 1000}, 25, 100000);
  grid.set_boxes(boxes);
  for (int q = 0; q < 200; ++q) {
    const double x = rng.uniform(-100, 1100), y = rng.uniform(-100, 1100), r = rng.uniform(1, 60);
    std::vector<std::size_t> visited;
    grid.for_each({x - r, y - r, x + r, y + r}, [&](std::size_t i) { visited.push_back(i); });
    std::vector<std::size_t> sorted = visited;
    std::sort(sorted.begin(), sorted.end());
    ASSERT_EQ(std::adjacent_find(sorted.begin(), sorted.end()), sorted.end()) << "a box twice";
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      const GridBox& b = boxes[i];
      const bool overlaps = b.min_x <= x + r && b.max_x >= x - r && b.min_y <= y + r && b.max_y >= y - r;
      ASSERT_TRUE(!overlaps || std::binary_search(sorted.begin(), sorted.end(), i)) << "missed box " << i;
    }
  }
}

TEST(SpatialGrid, RefusesABadLayoutAndHoldsTheCellCap) {
  SpatialGrid grid;
  EXPECT_THROW(grid.layout({0, 0, 10, 10}, 0, 10), std::invalid_argument);
  EXPECT_THROW(grid.layout({0, 0, 10, 10}, std::numeric_limits<double>::infinity(), 10), std::invalid_argument);
  EXPECT_THROW(grid.layout({0, 0, 10, 10}, 1, 0), std::invalid_argument);
  grid.layout({0, 0, 1e9, 3}, 1, 1000);  // a thin strip, a billion cells at side 1
  EXPECT_LE(grid.columns() * grid.rows(), 1000u);
  EXPECT_GE(grid.cell() * static_cast<double>(grid.columns()), 1e9);
  // A layout over a non-finite area falls back to one cell; points anywhere are still found.
  grid.layout({0, 0, std::numeric_limits<double>::infinity(), 1}, 1, 1000);
  EXPECT_EQ(grid.columns() * grid.rows(), 1u);
  const std::vector<Pose> points = {{1, 1, 0}, {-5, 1e300, 0}};
  grid.set_points(points);
  std::size_t found = 0;
  grid.for_each({0, 0, 2, 2}, [&](std::size_t) { ++found; });
  EXPECT_EQ(found, 2u);
  EXPECT_EQ(SpatialGrid::bounds(points).max_y, 1e300);
}

}  // namespace spatial_grid_test
}  // namespace symb::sim
