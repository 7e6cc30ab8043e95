#include "symb/sim/maze_generator.hpp"

#include <cmath>
#include <numbers>
#include <string>

namespace symb::sim {

using kernel::Error;

std::size_t maze_cells_for_robots(std::size_t robots) {
  const auto k = static_cast<std::size_t>(std::ceil(std::sqrt(2.0 * static_cast<double>(robots))));
  return k < 4 ? 4 : k;
}

namespace {

// Borders between cells. h[row * K + col], row 1..K-1: the border below cell (col, row), at
// y = row * size. v[row * K + col], col 1..K-1: the border left of cell (col, row), at x = col * size.
// Row 0 of h and column 0 of v are the arena's sides and never used.
struct Borders {
  std::size_t k;
  std::vector<char> h, v;
  explicit Borders(std::size_t size) : k(size), h(size * size, 1), v(size * size, 1) {}
};

void carve(Borders& b, kernel::RandomStream& random) {
  const std::size_t k = b.k;
  std::vector<char> visited(k * k, 0);
  std::vector<std::size_t> stack;
  stack.reserve(k * k);
  const auto first = static_cast<std::size_t>(random.below(k * k));
  visited[first] = 1;
  stack.push_back(first);
  while (!stack.empty()) {
    const std::size_t cell = stack.back();
    const std::size_t col = cell % k, row = cell / k;
    // Unvisited neighbours, in a fixed order, then one picked at random.
    std::size_t next[4];
    std::size_t n = 0;
    if (col > 0 && !visited[cell - 1]) next[n++] = cell - 1;
    if (col + 1 < k && !visited[cell + 1]) next[n++] = cell + 1;
    if (row > 0 && !visited[cell - k]) next[n++] = cell - k;
    if (row + 1 < k && !visited[cell + k]) next[n++] = cell + k;
    if (n == 0) {
      stack.pop_back();
      continue;
    }
    const std::size_t to = next[random.below(n)];
    if (to == cell - 1)
      b.v[cell] = 0;
    else if (to == cell + 1)
      b.v[to] = 0;
    else if (to + k == cell)
      b.h[cell] = 0;
    else
      b.h[to] = 0;
    visited[to] = 1;
    stack.push_back(to);
  }
}

void open_loops(Borders& b, double fraction, kernel::RandomStream& random) {
  const std::size_t k = b.k;
  std::vector<char*> inner;  // walls still standing between two cells, in a fixed order
  for (std::size_t row = 1; row < k; ++row)
    for (std::size_t col = 0; col < k; ++col)
      if (b.h[row * k + col]) inner.push_back(&b.h[row * k + col]);
  for (std::size_t row = 0; row < k; ++row)
    for (std::size_t col = 1; col < k; ++col)
      if (b.v[row * k + col]) inner.push_back(&b.v[row * k + col]);
  const auto remove = static_cast<std::size_t>(std::llround(fraction * static_cast<double>(inner.size())));
  // A partial Fisher-Yates shuffle: the first `remove` entries are a uniform random choice.
  for (std::size_t i = 0; i < remove; ++i) {
    const std::size_t j = i + static_cast<std::size_t>(random.below(inner.size() - i));
    std::swap(inner[i], inner[j]);
    *inner[i] = 0;
  }
}

}  // namespace

kernel::Result<Maze> generate_maze(const MazeOptions& o) {
  if (o.cells < 1 || o.cells > 1000) return Error{"maze: cells must be 1..1000, got " + std::to_string(o.cells)};
  if (!std::isfinite(o.cell_size) || o.cell_size <= 0)
    return Error{"maze: cell_size must be finite and positive, got " + std::to_string(o.cell_size)};
  if (!(o.loop_fraction >= 0 && o.loop_fraction <= 1))
    return Error{"maze: loop_fraction must be in [0, 1], got " + std::to_string(o.loop_fraction)};
  if (!std::isfinite(o.wall_thickness) || o.wall_thickness <= 0 || o.wall_thickness >= o.cell_size)
    return Error{"maze: wall_thickness must be positive and below cell_size, got " + std::to_string(o.wall_thickness)};
  if (!std::isfinite(o.wall_height) || o.wall_height <= 0)
    return Error{"maze: wall_height must be finite and positive, got " + std::to_string(o.wall_height)};

  const std::size_t k = o.cells;
  const double s = o.cell_size;
  kernel::RandomStream random(o.seed, 0x4d415a45 /* "MAZE" */);
  Borders b(k);
  carve(b, random);
  open_loops(b, o.loop_fraction, random);

  Maze m;
  m.cells = k;
  m.cell_size = s;
  m.world.width = m.world.height = static_cast<double>(k) * s;
  m.world.wall_height = o.wall_height;
  auto add = [&](double x1, double y1, double x2, double y2) {
    WallSpec w;
    w.x1 = x1, w.y1 = y1, w.x2 = x2, w.y2 = y2;
    w.thickness = o.wall_thickness;
    w.where.file = "<maze seed " + std::to_string(o.seed) + ">";
    m.world.walls.push_back(std::move(w));
  };
  const auto at = [s](std::size_t i) { return static_cast<double>(i) * s; };
  // Horizontal borders, line by line; a run of standing borders becomes one wall when merging.
  for (std::size_t row = 1; row < k; ++row) {
    std::size_t col = 0;
    while (col < k) {
      if (!b.h[row * k + col]) {
        ++col;
        continue;
      }
      std::size_t end = col + 1;
      if (o.merge_walls)
        while (end < k && b.h[row * k + end]) ++end;
      add(at(col), at(row), at(end), at(row));
      col = end;
    }
  }
  for (std::size_t col = 1; col < k; ++col) {
    std::size_t row = 0;
    while (row < k) {
      if (!b.v[row * k + col]) {
        ++row;
        continue;
      }
      std::size_t end = row + 1;
      if (o.merge_walls)
        while (end < k && b.v[end * k + col]) ++end;
      add(at(col), at(row), at(col), at(end));
      row = end;
    }
  }
  m.centres.reserve(k * k);
  for (std::size_t row = 0; row < k; ++row)
    for (std::size_t col = 0; col < k; ++col) m.centres.push_back(Pose{at(col) + s / 2, at(row) + s / 2, 0.0});
  return m;
}

kernel::Result<std::vector<Pose>> Maze::random_starts(std::size_t count, kernel::RandomStream& random) const {
  if (count > centres.size())
    return Error{"maze: " + std::to_string(count) + " robots do not fit in " + std::to_string(centres.size()) +
                 " cells (one robot per cell)"};
  std::vector<std::size_t> order(centres.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::vector<Pose> out;
  out.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t j = i + static_cast<std::size_t>(random.below(order.size() - i));
    std::swap(order[i], order[j]);
    Pose p = centres[order[i]];
    p.theta = random.uniform(-std::numbers::pi, std::numbers::pi);
    out.push_back(p);
  }
  return out;
}

}  // namespace symb::sim
