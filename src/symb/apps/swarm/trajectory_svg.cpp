#include "symb/apps/swarm/trajectory_svg.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "symb/apps/svg.hpp"

namespace symb::apps::swarm {

namespace {

constexpr double kSide = 800;             // px for the arena
constexpr double kTrajectoryMargin = 20;  // px around it

}  // namespace

void write_trajectory_svg(std::ostream& out, double arena, std::span<const TrajectoryLog> robots,
                          std::string_view caption) {
  const double scale = kSide / arena;
  // SVG's y axis points down; the arena's points up (north).
  const auto px = [&](double x) { return kTrajectoryMargin + x * scale; };
  const auto py = [&](double y) { return kTrajectoryMargin + (arena - y) * scale; };
  const double width = kSide + 2 * kTrajectoryMargin, height = kSide + 2 * kTrajectoryMargin + kSvgCaptionHeight;
  // Thinner, fainter lines when there are many robots, so that a crowd stays readable.
  const double stroke = robots.size() > 200 ? 0.6 : robots.size() > 30 ? 1.0 : 1.6;
  const double opacity = robots.size() > 200 ? 0.5 : 0.8;
  char buf[160];

  out << svg_picture_open(width, height);
  std::snprintf(buf, sizeof buf,
                "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"#f7f7f2\" stroke=\"#222\" "
                "stroke-width=\"3\"/>\n",
                kTrajectoryMargin, kTrajectoryMargin, kSide, kSide);
  out << buf;
  out << "<g fill=\"none\" stroke-linejoin=\"round\" stroke-linecap=\"round\">\n";
  for (std::size_t i = 0; i < robots.size(); ++i) {
    const TrajectoryLog& r = robots[i];
    const auto end = r.last();
    if (!end) continue;
    const std::string c = svg_colour(i);
    std::snprintf(buf, sizeof buf, R"(<polyline stroke="%s" stroke-width="%.1f" stroke-opacity="%.2f" points=")",
                  c.c_str(), stroke, opacity);
    out << buf;
    for (const TrajectoryPoint& p : r.points()) {
      std::snprintf(buf, sizeof buf, "%.1f,%.1f ", px(p.x), py(p.y));
      out << buf;
    }
    std::snprintf(buf, sizeof buf, "%.1f,%.1f\"/>\n", px(end->x), py(end->y));
    out << buf;
    if (!r.points().empty()) {
      std::snprintf(buf, sizeof buf, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"%.1f\" stroke=\"%s\" stroke-width=\"1\"/>\n",
                    px(r.points().front().x), py(r.points().front().y), 1.5 + stroke, c.c_str());
      out << buf;
    }
    std::snprintf(buf, sizeof buf, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"%.1f\" fill=\"%s\" stroke=\"none\"/>\n",
                  px(end->x), py(end->y), 2 + stroke, c.c_str());
    out << buf;
  }
  out << "</g>\n";
  std::snprintf(buf, sizeof buf, R"(<text x="%.1f" y="%.1f" font-family="sans-serif" font-size="14" fill="#222">)",
                kTrajectoryMargin, kSide + 2 * kTrajectoryMargin + 12);
  out << buf << svg_escape(caption) << "</text>\n</svg>\n";
}

}  // namespace symb::apps::swarm
