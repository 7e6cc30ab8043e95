// SpatialGrid: a uniform grid of square cells over a rectangle of the plane, each cell holding the
// indices of the items (robots, wall edges) that lie in it, so that a query near a point looks at a
// few cells instead of at every item. What IrModel and LocalRadio use to find what is near a robot
// in a swarm of thousands: the work of a query grows with the items near it, not with the swarm.
//
// Storage is flat (the counting-sort layout of a sparse matrix): `starts` (cells + 1 offsets) and
// `items` (cell by cell). Rebuilding from scratch costs O(items + cells) and allocates only when
// the grid grows past its largest size so far, so a world rebuilds its robots' grid every step.
// A point lies in one cell; a box in every cell its extent touches.
//
// Anything outside the rectangle, or not finite (poses come from physics), is clamped into the
// border cells (NaN into the first cell): it is still stored, and a query that reaches past the
// border visits those cells. Callers keep their exact test (distance, overlap) on the candidates.
//
// Deterministic: a query visits cells row by row, each cell's items by increasing index, and each
// item once (a box met in several cells is reported in the first of them the query visits).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "symb/sim/world_spec.hpp"

namespace symb::sim {

struct GridBox {
  double min_x = 0, min_y = 0, max_x = 0, max_y = 0;
};

class SpatialGrid {
 public:
  // Lays the grid out over `area` with square cells of side `cell` (> 0), wider when the area
  // would need more than `max_cells` (>= 1) of them. Drops the items. Throws
  // std::invalid_argument for a cell side that is not finite and positive, or max_cells == 0.
  void layout(const GridBox& area, double cell, std::size_t max_cells);

  // Item i is the point points[i]. Throws std::length_error beyond 2^32 - 1 items.
  void set_points(std::span<const Pose> points);
  // Item i is the box boxes[i] (min <= max on both axes), in every cell it touches.
  void set_boxes(std::span<const GridBox> boxes);

  // Calls visit(index) once for every item stored in a cell that `query` touches: every point
  // inside `query` and every box that overlaps it, and others near it (the caller tests).
  template <class Visit>
  void for_each(const GridBox& query, Visit&& visit) const;

  // The smallest box holding every finite point ({0, 0, 0, 0} when there is none).
  static GridBox bounds(std::span<const Pose> points);

  std::size_t columns() const { return columns_; }
  std::size_t rows() const { return rows_; }
  double cell() const { return cell_; }
  std::size_t item_count() const { return item_count_; }

 private:
  std::size_t column(double x) const { return clamp_index((x - area_.min_x) * inverse_cell_, columns_); }
  std::size_t row(double y) const { return clamp_index((y - area_.min_y) * inverse_cell_, rows_); }
  static std::size_t clamp_index(double f, std::size_t n) {
    if (!(f > 0)) return 0;  // below the area, or NaN
    if (f >= static_cast<double>(n)) return n - 1;
    return static_cast<std::size_t>(f);
  }

  void start(std::size_t items, bool boxes);
  void end_counts(std::size_t entries);

  GridBox area_;
  double cell_ = 1, inverse_cell_ = 1;
  std::size_t columns_ = 1, rows_ = 1;
  std::size_t item_count_ = 0;
  std::vector<std::uint32_t> starts_ = std::vector<std::uint32_t>(2, 0);  // cells + 1
  std::vector<std::uint32_t> items_;                                      // cell by cell
  // Points: each item's cell (scratch of set_points). Boxes: each item's first column and row.
  std::vector<std::uint32_t> cell_of_;
  std::vector<std::uint32_t> first_row_;
  bool boxes_ = false;
};

template <class Visit>
void SpatialGrid::for_each(const GridBox& query, Visit&& visit) const {
  const std::size_t c0 = column(query.min_x), c1 = std::max(c0, column(query.max_x));
  const std::size_t r0 = row(query.min_y), r1 = std::max(r0, row(query.max_y));
  for (std::size_t r = r0; r <= r1; ++r) {
    const std::size_t base = r * columns_;
    const std::uint32_t* item = items_.data() + starts_[base + c0];
    if (!boxes_) {  // the row's cells c0..c1 are contiguous in items_
      for (const std::uint32_t* end = items_.data() + starts_[base + c1 + 1]; item != end; ++item)
        visit(static_cast<std::size_t>(*item));
      continue;
    }
    // A box spans consecutive cells: report it in the first cell of the query it is in.
    for (std::size_t c = c0; c <= c1; ++c) {
      const std::uint32_t* cell_end = items_.data() + starts_[base + c + 1];
      for (; item != cell_end; ++item) {
        const std::uint32_t i = *item;
        if (std::max<std::size_t>(c0, cell_of_[i]) == c && std::max<std::size_t>(r0, first_row_[i]) == r)
          visit(static_cast<std::size_t>(i));
      }
    }
  }
}

}  // namespace symb::sim
