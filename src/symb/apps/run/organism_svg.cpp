#include "symb/apps/run/organism_svg.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "symb/apps/svg.hpp"

namespace symb::apps::run {

namespace {

using sim::mujoco::Pose3;
using sim::mujoco::Vec3;

constexpr double kOrganismLongSide = 900;  // px for the drawing's longer side
constexpr double kOrganismMargin = 50;     // px around it: room for the axis labels
constexpr double kTitle = 30;              // px above it
constexpr double kOrganismLegend = 120;    // px right of it for the modules' names
constexpr double kMinSpan = 0.3;           // m: a module that barely moved is still drawn at a readable size

struct Point2 {
  double u = 0, v = 0;
};

Vec3 rotate(const std::array<double, 4>& q, const Vec3& p) {
  // v' = v + 2w (r x v) + 2 r x (r x v), r the quaternion's vector part.
  const double w = q[0];
  const Vec3 r = {q[1], q[2], q[3]};
  const auto cross = [](const Vec3& a, const Vec3& b) {
    return Vec3{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  };
  const Vec3 t = cross(r, p);
  const Vec3 u = cross(r, t);
  return {p[0] + 2 * (w * t[0] + u[0]), p[1] + 2 * (w * t[1] + u[1]), p[2] + 2 * (w * t[2] + u[2])};
}

Point2 project(PathView view, const Vec3& p) {
  return view == PathView::kTop ? Point2{p[0], p[1]} : Point2{p[0], p[2]};
}

// The outline of one half of a module's box at its end pose, projected: the convex hull of the
// half's 8 corners (Andrew's monotone chain), counter-clockwise. The front half (x >= 0 in the
// module frame) is the module frame's body; the back half turns about the hinge axis through the
// centre by the hinge angle, as the model's joint does.
std::vector<Point2> half_outline(PathView view, const ModulePath& m, bool back) {
  const Vec3& size = m.box_size;
  const Pose3& pose = m.end;
  const double half = m.end_hinge_angle / 2;
  const double norm = std::hypot(m.hinge_axis[0], m.hinge_axis[1], m.hinge_axis[2]);
  const double s = norm > 0 ? std::sin(half) / norm : 0;
  const std::array<double, 4> hinge = {std::cos(half), s * m.hinge_axis[0], s * m.hinge_axis[1], s * m.hinge_axis[2]};
  std::vector<Point2> pts;
  for (int i = 0; i < 8; ++i) {
    const double x = (i & 1 ? 0.5 : 0.0) * size[0] * (back ? -1 : 1);
    Vec3 corner = {x, (i & 2 ? 0.5 : -0.5) * size[1], (i & 4 ? 0.5 : -0.5) * size[2]};
    if (back) corner = rotate(hinge, corner);
    const Vec3 r = rotate(pose.quaternion, corner);
    pts.push_back(project(view, {pose.position[0] + r[0], pose.position[1] + r[1], pose.position[2] + r[2]}));
  }
  std::sort(pts.begin(), pts.end(),
            [](const Point2& a, const Point2& b) { return a.u < b.u || (a.u == b.u && a.v < b.v); });
  const auto turn = [](const Point2& o, const Point2& a, const Point2& b) {
    return (a.u - o.u) * (b.v - o.v) - (a.v - o.v) * (b.u - o.u);
  };
  std::vector<Point2> hull(2 * pts.size());
  std::size_t k = 0;
  for (const Point2& p : pts) {
    while (k >= 2 && turn(hull[k - 2], hull[k - 1], p) <= 0) --k;
    hull[k++] = p;
  }
  for (std::size_t i = pts.size() - 1, lower = k + 1; i-- > 0;) {
    while (k >= lower && turn(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  hull.resize(k > 1 ? k - 1 : k);
  return hull;
}

// A lane picture's frame: title, one named lane per module, a time axis below. Returns the
// x of a time.
struct Lanes {
  static constexpr double kWidth = 900, kLeft = 110, kRight = 30, kTop = 40, kLane = 24, kBottom = 60;
  double end_time = 1;
  std::size_t count = 0;
  double x(double t) const { return kLeft + std::clamp(t / end_time, 0.0, 1.0) * (kWidth - kLeft - kRight); }
  double y(std::size_t lane) const { return kTop + kLane * (static_cast<double>(lane) + 0.5); }
  double bottom() const { return kTop + kLane * static_cast<double>(count); }
  double height() const { return bottom() + kBottom; }
};

Lanes open_lanes(std::ostream& out, const std::vector<std::string>& modules, double end_time, std::string_view title) {
  Lanes l;
  l.end_time = std::max(end_time, 1e-3);
  l.count = modules.size();
  char buf[256];
  out << svg_plot_open(Lanes::kWidth, l.height());
  out << "<text x=\"" << Lanes::kLeft << "\" y=\"24\" font-size=\"14\" fill=\"#222\">" << svg_escape(title)
      << "</text>\n";
  out << "<g fill=\"#222\">\n";
  for (std::size_t i = 0; i < modules.size(); ++i) {
    std::snprintf(buf, sizeof buf, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\">", Lanes::kLeft - 8, l.y(i) + 4);
    out << buf << svg_escape(modules[i]) << "</text>\n";
  }
  out << "</g>\n<g stroke=\"#ddd\" fill=\"#444\">\n";
  const double step = svg_tick_step(l.end_time, 8);
  for (double t = 0; t <= l.end_time + 1e-9; t += step) {
    std::snprintf(buf, sizeof buf,
                  "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>"
                  "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" stroke=\"none\">",
                  l.x(t), Lanes::kTop, l.x(t), l.bottom(), l.x(t), l.bottom() + 16);
    out << buf << svg_number(t) << "</text>\n";
  }
  std::snprintf(buf, sizeof buf,
                "</g>\n<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" fill=\"#444\">time (s)</text>\n",
                l.x(l.end_time / 2), l.bottom() + 34);
  out << buf;
  return l;
}

// The key below the lanes, and the end of the picture.
void close_lanes(std::ostream& out, const Lanes& l, std::string_view key) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "<text x=\"%.1f\" y=\"%.1f\" fill=\"#444\">", Lanes::kLeft, l.bottom() + 52);
  out << buf << svg_escape(key) << "</text>\n</svg>\n";
}

}  // namespace

void write_path_view_svg(std::ostream& out, PathView view, const std::vector<ModulePath>& modules,
                         const std::vector<DockedPair>& docked_at_end, std::string_view caption) {
  double u0 = std::numeric_limits<double>::infinity(), u1 = -u0, v0 = u0, v1 = -u0;
  std::vector<std::vector<Point2>> outlines;
  const auto grow = [&](const Point2& p) {
    u0 = std::min(u0, p.u), u1 = std::max(u1, p.u), v0 = std::min(v0, p.v), v1 = std::max(v1, p.v);
  };
  for (const ModulePath& m : modules) {
    for (const Vec3& p : m.points) grow(project(view, p));
    for (bool back : {false, true}) {
      outlines.push_back(half_outline(view, m, back));
      for (const Point2& p : outlines.back()) grow(p);
    }
  }
  if (view == PathView::kSide) grow({u0, 0.0});  // the floor in sight
  if (!(u0 <= u1)) u0 = v0 = 0, u1 = v1 = 0;
  const auto widen = [](double& lo, double& hi) {
    const double pad = std::max(0.05, 0.05 * (hi - lo));
    lo -= pad, hi += pad;
    if (hi - lo < kMinSpan) {
      const double mid = (lo + hi) / 2;
      lo = mid - kMinSpan / 2, hi = mid + kMinSpan / 2;
    }
  };
  widen(u0, u1);
  widen(v0, v1);
  const double scale = kOrganismLongSide / std::max(u1 - u0, v1 - v0);
  const double w = (u1 - u0) * scale, h = (v1 - v0) * scale;
  // SVG's y axis points down; the world's y (top) and z (side) point up.
  const auto px = [&](double u) { return kOrganismMargin + (u - u0) * scale; };
  const auto py = [&](double v) { return kTitle + kOrganismMargin / 2 + (v1 - v) * scale; };
  char buf[256];

  out << svg_plot_open(w + kOrganismMargin * 1.5 + kOrganismLegend, h + kTitle + kOrganismMargin * 1.5);
  out << "<text x=\"" << kOrganismMargin << "\" y=\"20\" font-size=\"14\" fill=\"#222\">"
      << (view == PathView::kTop ? "top view (x-y), " : "side view (x-z), ") << svg_escape(caption) << "</text>\n";
  // A metre grid, labelled.
  out << "<g stroke=\"#e4e4e4\" fill=\"#555\" font-size=\"10\">\n";
  const double step = svg_tick_step(std::max(u1 - u0, v1 - v0), 8);
  for (double u = std::ceil(u0 / step) * step; u <= u1; u += step) {
    std::snprintf(buf, sizeof buf,
                  "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/><text x=\"%.1f\" y=\"%.1f\" "
                  "text-anchor=\"middle\" stroke=\"none\">",
                  px(u), py(v1), px(u), py(v0), px(u), py(v0) + 14);
    out << buf << svg_number(u) << "</text>\n";
  }
  for (double v = std::ceil(v0 / step) * step; v <= v1; v += step) {
    std::snprintf(buf, sizeof buf,
                  "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/><text x=\"%.1f\" y=\"%.1f\" "
                  "text-anchor=\"end\" stroke=\"none\">",
                  px(u0), py(v), px(u1), py(v), px(u0) - 4, py(v) + 3);
    out << buf << svg_number(v) << "</text>\n";
  }
  std::snprintf(buf, sizeof buf,
                "</g>\n<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" fill=\"#444\">x (m)</text>\n"
                "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" fill=\"#444\" transform=\"rotate(-90 %.1f "
                "%.1f)\">%s (m)</text>\n",
                px((u0 + u1) / 2), py(v0) + 32, px(u0) - 36, py((v0 + v1) / 2), px(u0) - 36, py((v0 + v1) / 2),
                view == PathView::kTop ? "y" : "z");
  out << buf;
  if (view == PathView::kSide) {
    std::snprintf(buf, sizeof buf,
                  "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#8a7a5a\" stroke-width=\"2\"/>\n",
                  px(u0), py(0), px(u1), py(0));
    out << buf;
  }
  // End poses under the paths, then the paths, then the docked pairs over both.
  for (std::size_t i = 0; i < outlines.size(); ++i) {
    const std::string c = svg_colour(i / 2);  // two halves per module
    out << "<polygon fill=\"" << c << "\" fill-opacity=\"0.25\" stroke=\"" << c << "\" points=\"";
    for (const Point2& p : outlines[i]) {
      std::snprintf(buf, sizeof buf, "%.1f,%.1f ", px(p.u), py(p.v));
      out << buf;
    }
    out << "\"/>\n";
  }
  out << "<g fill=\"none\" stroke-linejoin=\"round\" stroke-linecap=\"round\">\n";
  for (std::size_t i = 0; i < modules.size(); ++i) {
    const ModulePath& m = modules[i];
    if (m.points.empty()) continue;
    const std::string c = svg_colour(i);
    out << "<polyline class=\"path\" data-module=\"" << svg_escape(m.name) << "\" stroke=\"" << c
        << "\" stroke-width=\"1.8\" points=\"";
    for (const Vec3& p : m.points) {
      const Point2 q = project(view, p);
      std::snprintf(buf, sizeof buf, "%.1f,%.1f ", px(q.u), py(q.v));
      out << buf;
    }
    out << "\"/>\n";
    const Point2 s = project(view, m.points.front());
    std::snprintf(buf, sizeof buf, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"5\" stroke=\"%s\" stroke-width=\"2\"/>\n",
                  px(s.u), py(s.v), c.c_str());
    out << buf;
  }
  out << "</g>\n<g stroke=\"#222\" stroke-width=\"4\" stroke-linecap=\"round\">\n";
  for (const DockedPair& d : docked_at_end) {
    if (d.a >= modules.size() || d.b >= modules.size()) continue;
    const Point2 a = project(view, modules[d.a].end.position), b = project(view, modules[d.b].end.position);
    std::snprintf(buf, sizeof buf, "<line class=\"dock\" x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>\n", px(a.u),
                  py(a.v), px(b.u), py(b.v));
    out << buf;
  }
  out << "</g>\n";
  // Legend: the modules' names in their colours.
  const double lx = px(u1) + 16;
  for (std::size_t i = 0; i < modules.size() && i < 40; ++i) {
    const double y = kTitle + kOrganismMargin / 2 + 8 + 16 * static_cast<double>(i);
    std::snprintf(buf, sizeof buf,
                  "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"%s\" stroke-width=\"3\"/>"
                  "<text x=\"%.1f\" y=\"%.1f\" fill=\"#222\">",
                  lx, y, lx + 20, y, svg_colour(i).c_str(), lx + 26, y + 4);
    out << buf << svg_escape(modules[i].name) << "</text>\n";
  }
  out << "</svg>\n";
}

void write_topology_svg(std::ostream& out, const std::vector<std::string>& modules,
                        const std::vector<TopologySpan>& spans, double end_time, std::string_view caption) {
  const Lanes l =
      open_lanes(out, modules, end_time, "organism topology (lanes coloured by docked group), " + std::string(caption));
  char buf[256];
  for (std::size_t s = 0; s < spans.size(); ++s) {
    const double t0 = spans[s].time, t1 = s + 1 < spans.size() ? spans[s + 1].time : l.end_time;
    const std::vector<std::size_t>& comp = spans[s].component;
    for (std::size_t m = 0; m < comp.size() && m < modules.size(); ++m) {
      const bool alone = std::count(comp.begin(), comp.end(), comp[m]) == 1;
      const std::string fill = alone ? std::string("#dddddd") : svg_colour(comp[m]);
      std::snprintf(
          buf, sizeof buf, "<rect class=\"span\" x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"%s\"/>\n",
          l.x(t0), l.y(m) - Lanes::kLane * 0.35, std::max(0.5, l.x(t1) - l.x(t0)), Lanes::kLane * 0.7, fill.c_str());
      out << buf;
    }
    if (s > 0) {
      std::snprintf(
          buf, sizeof buf,
          "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#222\" stroke-dasharray=\"3,3\"/>\n", l.x(t0),
          Lanes::kTop, l.x(t0), l.bottom());
      out << buf;
    }
  }
  close_lanes(out, l, "grey: alone; a colour per docked group (the colour of its first module); dashed: a change");
}

void write_docking_svg(std::ostream& out, const std::vector<std::string>& modules,
                       const std::vector<sim::mujoco::DockEvent>& events, double end_time, std::string_view caption) {
  using sim::mujoco::DockChange;
  const Lanes l = open_lanes(out, modules, end_time, "docking timeline, " + std::string(caption));
  char buf[320];
  for (const sim::mujoco::DockEvent& e : events) {
    if (e.module >= modules.size()) continue;
    const double x = l.x(e.time), y = l.y(e.module);
    const bool paired = e.other_module < modules.size() && e.change != DockChange::kRefused;
    if (e.change == DockChange::kRefused) {
      std::snprintf(buf, sizeof buf,
                    "<path class=\"refused\" d=\"M%.1f,%.1f l8,8 m0,-8 l-8,8\" stroke=\"#c0392b\" "
                    "stroke-width=\"2\"/>\n",
                    x - 4, y - 4);
      out << buf;
      continue;
    }
    const char* colour = e.change == DockChange::kLatched ? "#27ae60" : "#e67e22";
    if (paired) {
      std::snprintf(buf, sizeof buf,
                    "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"%s\" stroke-width=\"2\"/>\n", x, y,
                    x, l.y(e.other_module), colour);
      out << buf;
    }
    for (std::size_t m : {e.module, e.other_module}) {
      if (m >= modules.size() || (!paired && m != e.module)) continue;
      if (e.change == DockChange::kLatched)
        std::snprintf(buf, sizeof buf, "<circle class=\"latched\" cx=\"%.1f\" cy=\"%.1f\" r=\"5\" fill=\"%s\"/>\n", x,
                      l.y(m), colour);
      else
        std::snprintf(buf, sizeof buf,
                      "<rect class=\"unlatched\" x=\"%.1f\" y=\"%.1f\" width=\"9\" height=\"9\" fill=\"%s\"/>\n",
                      x - 4.5, l.y(m) - 4.5, colour);
      out << buf;
    }
  }
  close_lanes(out, l, "green dots: latched; orange squares: unlatched; red crosses: refused (docking.csv says why)");
}

}  // namespace symb::apps::run
