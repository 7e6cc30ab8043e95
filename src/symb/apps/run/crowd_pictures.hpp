// Pictures of a crowd (a 2D run of more than kCrowdRobots robots), which stay readable where a
// path per robot would be a blot:
//   density.svg      where the robots spent their time: the arena as a grid of cells, each
//                    coloured by the robot-seconds spent in it (a sequential scale, its legend
//                    beside the arena), walls on top
//   trails.svg       the paths of a seeded sample of robots (maze_svg.hpp), every robot's end
//                    position as a grey dot beneath
//   robot_stats.csv  per robot: distance, contacts, contact steps, time moving, mean speed, end
//   robot_stats.svg  histograms of distance, contacts and mean speed over the robots
// DensityGrid gathers the counts while the run steps; the writers run once at the end.
#pragma once

#include <cstdint>
#include <ostream>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "symb/sim/world_spec.hpp"

namespace symb::apps::run {

struct RobotSummary;

// Robot-steps per cell of a grid over the arena [0, width] x [0, height] (cm), `cells` cells
// along its longer side (square cells). A point outside the arena counts in the nearest cell.
class DensityGrid {
 public:
  DensityGrid(double width, double height, std::size_t cells);
  void add(double x, double y);

  std::size_t columns() const { return nx_; }
  std::size_t rows() const { return ny_; }
  double cell() const { return cell_; }  // cm
  std::uint64_t at(std::size_t column, std::size_t row) const { return counts_[row * nx_ + column]; }
  std::uint64_t total() const { return total_; }
  std::uint64_t max() const;

 private:
  double cell_;
  std::size_t nx_, ny_;
  std::vector<std::uint64_t> counts_;
  std::uint64_t total_ = 0;
};

// Cells along the arena's longer side in a crowd's density.svg.
inline constexpr std::size_t kDensityCells = 80;

// density.svg. `step_seconds` turns a count into robot-seconds. Each drawn cell, or run of equal
// cells along a row, is a <rect class="cell" data-level="L"> (L of kDensityLevels - 1 the top of
// the scale); the legend is <g id="legend">.
inline constexpr int kDensityLevels = 64;
void write_density_svg(std::ostream& out, const sim::WorldSpec& world, const DensityGrid& grid, double step_seconds,
                       std::string_view caption);

// robot_stats.csv: `robot,distance_m,contacts,contact_steps,moving_s,mean_speed_cm_s,end_x_cm,end_y_cm`.
std::string robot_stats_csv(std::span<const RobotSummary> robots, double simulated_seconds);
// robot_stats.svg: three histograms side by side; each bar a <rect class="bar" data-count="N">.
void write_robot_stats_svg(std::ostream& out, std::span<const RobotSummary> robots, double simulated_seconds,
                           std::string_view caption);

}  // namespace symb::apps::run
