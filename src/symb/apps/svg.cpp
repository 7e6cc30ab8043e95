#include "symb/apps/svg.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace symb::apps {

namespace {

// The XML declaration, the <svg> element w x h with `attributes` added, and `background`.
std::string svg_open(double w, double h, const char* attributes, const char* background) {
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
                "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"%.0f\" height=\"%.0f\" "
                "viewBox=\"0 0 %.0f %.0f\"%s>\n%s\n",
                w, h, w, h, attributes, background);
  return buf;
}

}  // namespace

std::string svg_colour(std::size_t i) {
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

std::string svg_escape(std::string_view text) {
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

std::string svg_plot_open(double w, double h) {
  return svg_open(w, h, R"( font-family="sans-serif" font-size="12")",
                  R"(<rect width="100%" height="100%" fill="white"/>)");
}

std::string svg_picture_open(double w, double h) {
  return svg_open(w, h, "", R"(<rect x="0" y="0" width="100%" height="100%" fill="white"/>)");
}

double svg_tick_step(double span, int count) {
  const double raw = span / count;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p >= raw) return m * p;
  return 10 * p;
}

std::string svg_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", std::fabs(v) < 1e-12 ? 0.0 : v);
  return buf;
}

}  // namespace symb::apps
