#include "symb/apps/run/crowd_pictures.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include "symb/apps/cli_args.hpp"
#include "symb/apps/run/run_recorder.hpp"
#include "symb/apps/svg.hpp"

namespace symb::apps::run {

namespace {

constexpr double kCrowdLongSide = 900;  // px for the arena's longer side, as maze_svg
constexpr double kCrowdMargin = 20;
constexpr double kCrowdLegend = 130;  // px right of the arena
constexpr int kBins = 20;             // per histogram

// Viridis at ten even steps: sequential, perceptually even, readable in grey and by the colour-blind.
constexpr std::array<std::array<int, 3>, 10> kViridis = {{{0x44, 0x01, 0x54},
                                                          {0x48, 0x28, 0x78},
                                                          {0x3e, 0x49, 0x89},
                                                          {0x31, 0x68, 0x8e},
                                                          {0x26, 0x82, 0x8e},
                                                          {0x1f, 0x9e, 0x89},
                                                          {0x35, 0xb7, 0x79},
                                                          {0x6e, 0xce, 0x58},
                                                          {0xb5, 0xde, 0x2b},
                                                          {0xfd, 0xe7, 0x25}}};

// The colour of level `l` in [0, kDensityLevels).
std::string level_colour(int l) {
  const double t = static_cast<double>(l) / (kDensityLevels - 1) * (kViridis.size() - 1);
  const std::size_t i = std::min<std::size_t>(static_cast<std::size_t>(t), kViridis.size() - 2);
  const double f = t - static_cast<double>(i);
  char buf[8];
  const auto mix = [&](int k) {
    return static_cast<int>(std::lround(kViridis[i][k] + f * (kViridis[i + 1][k] - kViridis[i][k])));
  };
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", mix(0), mix(1), mix(2));
  return buf;
}

struct Frame {
  double scale, w, h;
  double px(double x) const { return kCrowdMargin + x * scale; }
  double py(double y, double height) const { return kCrowdMargin + (height - y) * scale; }
};

void draw_walls(std::ostream& out, const sim::WorldSpec& world, const Frame& f) {
  char buf[200];
  out << "<g stroke=\"#ddd\" stroke-linecap=\"square\">\n";
  for (const sim::WallSpec& wall : world.walls) {
    std::snprintf(buf, sizeof buf, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke-width=\"%.1f\"/>\n",
                  f.px(wall.x1), f.py(wall.y1, world.height), f.px(wall.x2), f.py(wall.y2, world.height),
                  std::max(1.0, wall.thickness * f.scale));
    out << buf;
  }
  out << "</g>\n";
}

struct Stat {
  const char* title;
  std::vector<double> values;
};

}  // namespace

DensityGrid::DensityGrid(double width, double height, std::size_t cells) {
  const double longer = std::max({width, height, 1.0});
  cell_ = longer / static_cast<double>(std::max<std::size_t>(cells, 1));
  nx_ = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(width / cell_ - 1e-9)));
  ny_ = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(height / cell_ - 1e-9)));
  counts_.assign(nx_ * ny_, 0);
}

void DensityGrid::add(double x, double y) {
  const auto index = [this](double v, std::size_t n) {
    const double c = std::floor(v / cell_);
    return c <= 0 ? std::size_t{0} : std::min(n - 1, static_cast<std::size_t>(c));
  };
  ++counts_[index(y, ny_) * nx_ + index(x, nx_)];
  ++total_;
}

std::uint64_t DensityGrid::max() const {
  return counts_.empty() ? 0 : *std::max_element(counts_.begin(), counts_.end());
}

void write_density_svg(std::ostream& out, const sim::WorldSpec& world, const DensityGrid& grid, double step_seconds,
                       std::string_view caption) {
  const double longer = std::max({world.width, world.height, 1.0});
  const Frame f{kCrowdLongSide / longer, world.width * (kCrowdLongSide / longer),
                world.height * (kCrowdLongSide / longer)};
  const double top = static_cast<double>(grid.max());
  char buf[240];
  out << svg_picture_open(f.w + 2 * kCrowdMargin + kCrowdLegend, f.h + 2 * kCrowdMargin + kSvgCaptionHeight);
  std::snprintf(buf, sizeof buf,
                "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"#f7f7f2\" stroke=\"#333\"/>\n",
                kCrowdMargin, kCrowdMargin, f.w, f.h);
  out << buf;
  // Linear scale from 0 to the busiest cell: level 0 is a cell visited at all (empty cells keep
  // the floor's colour), the top level the busiest. Equal neighbours along a row share a rect.
  out << "<g id=\"density\" stroke=\"none\">\n";
  for (std::size_t row = 0; row < grid.rows(); ++row) {
    const double y1 = std::min(world.height, grid.cell() * static_cast<double>(row + 1));
    const double y0 = grid.cell() * static_cast<double>(row);
    for (std::size_t c = 0; c < grid.columns();) {
      const std::uint64_t n = grid.at(c, row);
      if (n == 0) {
        ++c;
        continue;
      }
      const int level = std::clamp(static_cast<int>(std::ceil(static_cast<double>(n) / top * kDensityLevels)) - 1, 0,
                                   kDensityLevels - 1);
      std::size_t end = c + 1;
      const auto level_of = [&](std::size_t k) {
        const std::uint64_t m = grid.at(k, row);
        return m == 0 ? -1
                      : std::clamp(static_cast<int>(std::ceil(static_cast<double>(m) / top * kDensityLevels)) - 1, 0,
                                   kDensityLevels - 1);
      };
      while (end < grid.columns() && level_of(end) == level) ++end;
      const double x0 = static_cast<double>(c) * grid.cell();
      const double x1 = std::min(world.width, static_cast<double>(end) * grid.cell());
      std::snprintf(buf, sizeof buf,
                    "<rect class=\"cell\" data-level=\"%d\" x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" "
                    "fill=\"%s\"/>\n",
                    level, f.px(x0), f.py(y1, world.height), (x1 - x0) * f.scale, (y1 - y0) * f.scale,
                    level_colour(level).c_str());
      out << buf;
      c = end;
    }
  }
  out << "</g>\n";
  draw_walls(out, world, f);

  // The legend: the colour bar from 0 (bottom) to the busiest cell (top), ticks in robot-seconds.
  const double lx = f.w + 2 * kCrowdMargin + 10, bar_top = kCrowdMargin + 30, bar_h = std::min(300.0, f.h - 40);
  const double top_seconds = top * step_seconds;
  out << "<g id=\"legend\" font-family=\"sans-serif\" font-size=\"11\" fill=\"#222\">\n";
  std::snprintf(buf, sizeof buf, "<text x=\"%.1f\" y=\"%.1f\">robot-seconds</text>\n", lx, kCrowdMargin + 8);
  out << buf;
  std::snprintf(
      buf, sizeof buf, "<text x=\"%.1f\" y=\"%.1f\">per %s cm cell</text>\n", lx, kCrowdMargin + 21,
      (svg_number(std::round(grid.cell() * 10) / 10) + " x " + svg_number(std::round(grid.cell() * 10) / 10)).c_str());
  out << buf;
  for (int l = 0; l < kDensityLevels; ++l) {
    const double h = bar_h / kDensityLevels;
    std::snprintf(buf, sizeof buf, "<rect x=\"%.1f\" y=\"%.2f\" width=\"18\" height=\"%.2f\" fill=\"%s\"/>\n", lx,
                  bar_top + bar_h - (l + 1) * h, h + 0.3, level_colour(l).c_str());
    out << buf;
  }
  if (top_seconds > 0) {
    const double step = svg_tick_step(top_seconds, 5);
    for (double v = 0; v <= top_seconds * (1 + 1e-9); v += step) {
      const double y = bar_top + bar_h - v / top_seconds * bar_h;
      std::snprintf(buf, sizeof buf,
                    "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#222\"/><text class=\"tick\" "
                    "x=\"%.1f\" y=\"%.1f\">%s</text>\n",
                    lx + 18, y, lx + 23, y, lx + 26, y + 4, svg_number(v).c_str());
      out << buf;
    }
  }
  std::snprintf(buf, sizeof buf, "<text x=\"%.1f\" y=\"%.1f\">max %s</text>\n", lx, bar_top + bar_h + 18,
                fixed(top_seconds, 2).c_str());
  out << buf << "</g>\n";
  std::snprintf(buf, sizeof buf, R"(<text x="%.1f" y="%.1f" font-family="sans-serif" font-size="14" fill="#222">)",
                kCrowdMargin, f.h + 2 * kCrowdMargin + 14);
  out << buf << svg_escape(caption) << "</text>\n</svg>\n";
}

std::string robot_stats_csv(std::span<const RobotSummary> robots, double simulated_seconds) {
  std::string s = "robot,distance_m,contacts,contact_steps,moving_s,mean_speed_cm_s,end_x_cm,end_y_cm\n";
  for (const RobotSummary& r : robots)
    s += r.name + "," + fixed(r.distance / 100, 3) + "," + std::to_string(r.contact_events) + "," +
         std::to_string(r.contact_steps) + "," + fixed(r.moving_seconds, 2) + "," +
         fixed(simulated_seconds > 0 ? r.distance / simulated_seconds : 0.0, 3) + "," + fixed(r.end.x, 1) + "," +
         fixed(r.end.y, 1) + "\n";
  return s;
}

void write_robot_stats_svg(std::ostream& out, std::span<const RobotSummary> robots, double simulated_seconds,
                           std::string_view caption) {
  Stat stats[3] = {{"distance (m)", {}}, {"contacts begun", {}}, {"mean speed (cm/s)", {}}};
  for (const RobotSummary& r : robots) {
    stats[0].values.push_back(r.distance / 100);
    stats[1].values.push_back(static_cast<double>(r.contact_events));
    stats[2].values.push_back(simulated_seconds > 0 ? r.distance / simulated_seconds : 0.0);
  }
  constexpr double kPanelW = 320, kPanelH = 240, kPad = 45;
  char buf[260];
  out << svg_plot_open(3 * kPanelW + kCrowdMargin, kPanelH + 2 * kCrowdMargin + kSvgCaptionHeight + 20);
  for (int p = 0; p < 3; ++p) {
    std::vector<double>& v = stats[p].values;
    std::sort(v.begin(), v.end());
    const double x0 = kCrowdMargin + p * kPanelW + kPad, y0 = kCrowdMargin + 20, w = kPanelW - kPad - 15,
                 h = kPanelH - 40;
    out << "<g class=\"histogram\">\n";
    std::snprintf(buf, sizeof buf, "<text x=\"%.1f\" y=\"%.1f\" font-weight=\"bold\">%s</text>\n", x0, kCrowdMargin + 8,
                  stats[p].title);
    out << buf;
    if (v.empty()) {
      out << "</g>\n";
      continue;
    }
    const double lo = v.front(), hi = v.back();
    // Counts are integers: a bin per value when they span fewer than kBins.
    const bool integral = p == 1;
    const int bins = integral ? static_cast<int>(std::min<double>(kBins, hi - lo + 1)) : (hi > lo ? kBins : 1);
    const double width = integral ? std::max(1.0, std::ceil((hi - lo + 1) / bins)) : (hi > lo ? (hi - lo) / bins : 1);
    std::vector<std::size_t> counts(static_cast<std::size_t>(bins), 0);
    for (double x : v)
      ++counts[static_cast<std::size_t>(std::clamp(static_cast<int>(std::floor((x - lo) / width)), 0, bins - 1))];
    const double peak = static_cast<double>(*std::max_element(counts.begin(), counts.end()));
    const double span = integral ? width * bins : (hi > lo ? hi - lo : 1);
    for (int b = 0; b < bins; ++b) {
      const double bh = static_cast<double>(counts[static_cast<std::size_t>(b)]) / peak * h;
      std::snprintf(buf, sizeof buf,
                    "<rect class=\"bar\" data-count=\"%zu\" x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" "
                    "fill=\"#3e6fb0\" stroke=\"white\" stroke-width=\"0.5\"/>\n",
                    counts[static_cast<std::size_t>(b)], x0 + b * w / bins, y0 + h - bh, w / bins, bh);
      out << buf;
    }
    // Axes: robots up, the quantity along; ticks at nice steps.
    std::snprintf(buf, sizeof buf, "<path d=\"M%.1f %.1fV%.1fH%.1f\" fill=\"none\" stroke=\"#222\"/>\n", x0, y0, y0 + h,
                  x0 + w);
    out << buf;
    const double xs = svg_tick_step(span, 4);
    for (double t = std::ceil(lo / xs) * xs; t <= lo + span * (1 + 1e-9); t += xs) {
      const double x = x0 + (t - lo) / span * w;
      std::snprintf(buf, sizeof buf, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">%s</text>\n", x, y0 + h + 15,
                    svg_number(t).c_str());
      out << buf;
    }
    const double ys = std::max(1.0, svg_tick_step(peak, 4));
    for (double t = 0; t <= peak; t += ys) {
      std::snprintf(buf, sizeof buf, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\">%s</text>\n", x0 - 5,
                    y0 + h - t / peak * h + 4, svg_number(t).c_str());
      out << buf;
    }
    double mean = 0;
    for (double x : v) mean += x;
    mean /= static_cast<double>(v.size());
    std::snprintf(buf, sizeof buf, "<text x=\"%.1f\" y=\"%.1f\">robots: %zu, mean %s, median %s</text>\n", x0,
                  y0 + h + 32, v.size(), fixed(mean, 2).c_str(), fixed(v[v.size() / 2], 2).c_str());
    out << buf << "</g>\n";
  }
  std::snprintf(buf, sizeof buf, R"(<text x="%.1f" y="%.1f" font-size="14" fill="#222">)", kCrowdMargin,
                kPanelH + 2 * kCrowdMargin + 30);
  out << buf << svg_escape(caption) << "</text>\n</svg>\n";
}

}  // namespace symb::apps::run
