#include "symb/sim/spatial_grid.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace symb::sim {

namespace {

constexpr std::size_t kMaxItems = std::numeric_limits<std::uint32_t>::max();

bool finite(const GridBox& b) {
  return std::isfinite(b.min_x) && std::isfinite(b.min_y) && std::isfinite(b.max_x) && std::isfinite(b.max_y);
}

// Cells along an extent of `length` with side `cell`: at least one.
double cells_along(double length, double cell) { return std::max(1.0, std::ceil(length / cell)); }

}  // namespace

void SpatialGrid::layout(const GridBox& area, double cell, std::size_t max_cells) {
  if (!(std::isfinite(cell) && cell > 0))
    throw std::invalid_argument("spatial grid: the cell side must be finite and positive");
  if (max_cells == 0) throw std::invalid_argument("spatial grid: max_cells must be at least 1");
  area_ = finite(area) && area.max_x >= area.min_x && area.max_y >= area.min_y ? area : GridBox{};
  const double width = area_.max_x - area_.min_x, height = area_.max_y - area_.min_y;
  const auto limit = static_cast<double>(max_cells);
  if (cells_along(width, cell) * cells_along(height, cell) > limit) {
    // Cells of this side hold the area in about max_cells; widened further while rounding up
    // the counts of columns and rows still asks for too many.
    cell = std::max({cell, std::sqrt(width * height / limit), width / limit, height / limit});
    while (cells_along(width, cell) * cells_along(height, cell) > limit) cell *= 1.0625;
  }
  cell_ = cell;
  inverse_cell_ = 1 / cell;
  columns_ = static_cast<std::size_t>(cells_along(width, cell));
  rows_ = static_cast<std::size_t>(cells_along(height, cell));
  starts_.assign(columns_ * rows_ + 1, 0);
  items_.clear();
  cell_of_.clear();
  first_row_.clear();
  item_count_ = 0;
  boxes_ = false;
}

// Counting sort, in three passes: count each cell's entries into starts_ (start()), turn the
// counts into running sums, the end of each cell (end_counts()), then place the entries from the
// last item down, each one at --starts_[cell], so that every cell ends up in increasing index
// order and starts_[c] at its beginning.
void SpatialGrid::start(std::size_t items, bool boxes) {
  if (items > kMaxItems) throw std::length_error("spatial grid: more than 2^32 - 1 items");
  boxes_ = boxes;
  item_count_ = items;
  cell_of_.resize(items);
  std::fill(starts_.begin(), starts_.end(), 0);
}

void SpatialGrid::end_counts(std::size_t entries) {
  const std::size_t cells = columns_ * rows_;
  for (std::size_t c = 1; c < cells; ++c) starts_[c] += starts_[c - 1];
  starts_[cells] = static_cast<std::uint32_t>(entries);
  items_.resize(entries);
}

void SpatialGrid::set_points(std::span<const Pose> points) {
  start(points.size(), false);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto c = static_cast<std::uint32_t>(row(points[i].y) * columns_ + column(points[i].x));
    cell_of_[i] = c;
    ++starts_[c];
  }
  end_counts(points.size());
  for (std::size_t i = points.size(); i-- > 0;) items_[--starts_[cell_of_[i]]] = static_cast<std::uint32_t>(i);
}

void SpatialGrid::set_boxes(std::span<const GridBox> boxes) {
  start(boxes.size(), true);
  first_row_.resize(boxes.size());
  auto each_cell = [&](std::size_t i, auto&& f) {
    const GridBox& b = boxes[i];
    const std::size_t c0 = column(b.min_x), c1 = std::max(c0, column(b.max_x));
    const std::size_t r0 = row(b.min_y), r1 = std::max(r0, row(b.max_y));
    for (std::size_t r = r0; r <= r1; ++r)
      for (std::size_t c = c0; c <= c1; ++c) f(r * columns_ + c);
  };
  std::size_t entries = 0;
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    cell_of_[i] = static_cast<std::uint32_t>(column(boxes[i].min_x));
    first_row_[i] = static_cast<std::uint32_t>(row(boxes[i].min_y));
    each_cell(i, [&](std::size_t c) {
      ++starts_[c];
      ++entries;
    });
    if (entries > kMaxItems) throw std::length_error("spatial grid: more than 2^32 - 1 box entries");
  }
  end_counts(entries);
  for (std::size_t i = boxes.size(); i-- > 0;)
    each_cell(i, [&](std::size_t c) { items_[--starts_[c]] = static_cast<std::uint32_t>(i); });
}

GridBox SpatialGrid::bounds(std::span<const Pose> points) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  GridBox b{inf, inf, -inf, -inf};
  for (const Pose& p : points) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) continue;
    b.min_x = std::min(b.min_x, p.x);
    b.min_y = std::min(b.min_y, p.y);
    b.max_x = std::max(b.max_x, p.x);
    b.max_y = std::max(b.max_y, p.y);
  }
  return b.min_x <= b.max_x ? b : GridBox{};
}

}  // namespace symb::sim
