#include "symb/apps/run/maze_svg.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "symb/apps/svg.hpp"

namespace symb::apps::run {

namespace {

constexpr double kMazeLongSide = 900;  // px for the arena's longer side
constexpr double kMazeMargin = 20;     // px around it

}  // namespace

void write_maze_svg(std::ostream& out, const sim::WorldSpec& world, std::span<const RobotPath> robots,
                    std::string_view caption, std::span<const PathPoint> backdrop) {
  const double longer = std::max({world.width, world.height, 1.0});
  const double scale = kMazeLongSide / longer;
  const double w = world.width * scale, h = world.height * scale;
  // SVG's y axis points down; the world's points up.
  const auto px = [&](double x) { return kMazeMargin + x * scale; };
  const auto py = [&](double y) { return kMazeMargin + (world.height - y) * scale; };
  const double stroke = robots.size() > 30 ? 1.0 : 1.8;
  char buf[200];

  out << svg_picture_open(w + 2 * kMazeMargin, h + 2 * kMazeMargin + kSvgCaptionHeight);
  std::snprintf(buf, sizeof buf,
                "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"#f7f7f2\" stroke=\"#333\" "
                "stroke-width=\"%.1f\"/>\n",
                kMazeMargin, kMazeMargin, w, h, std::max(2.0, 2.0 * scale));
  out << buf;
  // Floor zones under everything, in their own grey (0 black .. 1 the floor's white), labelled.
  for (const sim::ZoneSpec& z : world.zones) {
    const int g = static_cast<int>(std::lround(80 + 160 * std::clamp(z.ground, 0.0, 1.0)));
    char fill[8];
    std::snprintf(fill, sizeof fill, "#%02x%02x%02x", g, g, g);
    if (z.shape == sim::ZoneSpec::Shape::kRect)
      std::snprintf(buf, sizeof buf, "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"%s\"/>\n",
                    px(z.x1), py(z.y2), (z.x2 - z.x1) * scale, (z.y2 - z.y1) * scale, fill);
    else
      std::snprintf(buf, sizeof buf, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"%.1f\" fill=\"%s\"/>\n", px(z.cx), py(z.cy),
                    z.radius * scale, fill);
    out << buf;
    if (!z.name.empty()) {
      const double lx = z.shape == sim::ZoneSpec::Shape::kRect ? px(z.x1) + 3 : px(z.cx - z.radius) + 3;
      const double ly = z.shape == sim::ZoneSpec::Shape::kRect ? py(z.y2) + 13 : py(z.cy) + 4;
      std::snprintf(buf, sizeof buf, R"(<text x="%.1f" y="%.1f" font-family="sans-serif" font-size="11" fill="#000">)",
                    lx, ly);
      out << buf << svg_escape(z.name) << "</text>\n";
    }
  }
  // Square caps reach half the stroke width past each end: the drawn wall is its segment plus its
  // thickness long, as the solid wall is (enki_world.cpp adds the thickness to the box's length).
  out << "<g stroke=\"#333\" stroke-linecap=\"square\">\n";
  for (const sim::WallSpec& wall : world.walls) {
    std::snprintf(buf, sizeof buf, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke-width=\"%.1f\"/>\n",
                  px(wall.x1), py(wall.y1), px(wall.x2), py(wall.y2), std::max(1.0, wall.thickness * scale));
    out << buf;
  }
  out << "</g>\n";
  if (!backdrop.empty()) {
    out << "<g id=\"backdrop\" fill=\"#aaa\" stroke=\"none\">\n";
    for (const PathPoint& p : backdrop) {
      std::snprintf(buf, sizeof buf, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"2\"/>\n", px(p.x), py(p.y));
      out << buf;
    }
    out << "</g>\n";
  }
  out << "<g fill=\"none\" stroke-linejoin=\"round\" stroke-linecap=\"round\">\n";
  for (std::size_t i = 0; i < robots.size(); ++i) {
    const RobotPath& r = robots[i];
    if (r.points.empty()) continue;
    const std::string c = svg_colour(i);
    std::snprintf(buf, sizeof buf, R"(<polyline stroke="%s" stroke-width="%.1f" stroke-opacity="0.85" points=")",
                  c.c_str(), stroke);
    out << buf;
    for (const PathPoint& p : r.points) {
      std::snprintf(buf, sizeof buf, "%.1f,%.1f ", px(p.x), py(p.y));
      out << buf;
    }
    out << "\"/>\n";
    std::snprintf(buf, sizeof buf, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"5\" stroke=\"%s\" stroke-width=\"2\"/>\n",
                  px(r.points.front().x), py(r.points.front().y), c.c_str());
    out << buf;
    std::snprintf(buf, sizeof buf, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"4\" fill=\"%s\" stroke=\"none\"/>\n",
                  px(r.points.back().x), py(r.points.back().y), c.c_str());
    out << buf;
    for (const PathPoint& p : r.contacts) {
      std::snprintf(buf, sizeof buf, "<path d=\"M%.1f %.1fl8 8m0 -8l-8 8\" stroke=\"#d00\" stroke-width=\"2\"/>\n",
                    px(p.x) - 4, py(p.y) - 4);
      out << buf;
    }
  }
  out << "</g>\n";
  std::snprintf(buf, sizeof buf, R"(<text x="%.1f" y="%.1f" font-family="sans-serif" font-size="14" fill="#222">)",
                kMazeMargin, h + 2 * kMazeMargin + 14);
  out << buf << svg_escape(caption) << "</text>\n</svg>\n";
}

}  // namespace symb::apps::run
