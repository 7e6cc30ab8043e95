#include "symb/apps/swarm/trajectory_svg.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace symb::apps::swarm {

namespace {

constexpr double kSide = 800;    // px for the arena
constexpr double kMargin = 20;   // px around it
constexpr double kCaption = 28;  // px below it

// The i-th of a sequence of well-separated hues (golden-angle steps), as #rrggbb.
std::string colour(std::size_t i) {
  const double h = std::fmod(static_cast<double>(i) * 137.50776405, 360.0) / 60.0;
  const double s = 0.75, l = i % 2 == 0 ? 0.42 : 0.55;
  const double c = (1 - std::fabs(2 * l - 1)) * s;
  const double x = c * (1 - std::fabs(std::fmod(h, 2.0) - 1));
  double r = 0, g = 0, b = 0;
  switch (static_cast<int>(h)) {
    case 0: r = c, g = x; break;
    case 1: r = x, g = c; break;
    case 2: g = c, b = x; break;
    case 3: g = x, b = c; break;
    case 4: r = x, b = c; break;
    default: r = c, b = x; break;
  }
  const double m = l - c / 2;
  char buf[8];
  const auto byte = [&](double v) { return static_cast<unsigned>(std::lround(std::clamp(v + m, 0.0, 1.0) * 255)); };
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", byte(r), byte(g), byte(b));
  return buf;
}

std::string escape(std::string_view text) {
  std::string s;
  for (char ch : text) {
    switch (ch) {
      case '&': s += "&amp;"; break;
      case '<': s += "&lt;"; break;
      case '>': s += "&gt;"; break;
      default: s += ch;
    }
  }
  return s;
}

}  // namespace

void write_trajectory_svg(std::ostream& out, double arena, std::span<const TrajectoryLog> robots,
                          std::string_view caption) {
  const double scale = kSide / arena;
  // SVG's y axis points down; the arena's points up (north).
  const auto px = [&](double x) { return kMargin + x * scale; };
  const auto py = [&](double y) { return kMargin + (arena - y) * scale; };
  const double width = kSide + 2 * kMargin, height = kSide + 2 * kMargin + kCaption;
  // Thinner, fainter lines when there are many robots, so that a crowd stays readable.
  const double stroke = robots.size() > 200 ? 0.6 : robots.size() > 30 ? 1.0 : 1.6;
  const double opacity = robots.size() > 200 ? 0.5 : 0.8;
  char buf[160];

  out << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  std::snprintf(buf, sizeof buf,
                "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"%.0f\" height=\"%.0f\" "
                "viewBox=\"0 0 %.0f %.0f\">\n",
                width, height, width, height);
  out << buf;
  out << "<rect x=\"0\" y=\"0\" width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  std::snprintf(buf, sizeof buf,
                "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"#f7f7f2\" stroke=\"#222\" "
                "stroke-width=\"3\"/>\n",
                kMargin, kMargin, kSide, kSide);
  out << buf;
  out << "<g fill=\"none\" stroke-linejoin=\"round\" stroke-linecap=\"round\">\n";
  for (std::size_t i = 0; i < robots.size(); ++i) {
    const TrajectoryLog& r = robots[i];
    const auto end = r.last();
    if (!end) continue;
    const std::string c = colour(i);
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
                kMargin, kSide + 2 * kMargin + 12);
  out << buf << escape(caption) << "</text>\n</svg>\n";
}

}  // namespace symb::apps::swarm
