#include "symb/apps/run/probe_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "symb/apps/svg.hpp"

namespace symb::apps::run {

namespace {

constexpr double kWidth = 900, kHeight = 360;
constexpr double kLeft = 70, kRight = 150, kTop = 36, kBottom = 44;  // room for axes and legend
constexpr std::size_t kMaxLegend = 16;

}  // namespace

std::string probe_file_name(const ProbeSeries& series) {
  std::string name = series.robot + "." + series.task + "." + series.channel;
  for (char& c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.')) c = '_';
  return name + ".svg";
}

void write_probe_svg(std::ostream& out, const ProbeSeries& s) {
  double t0 = 0, t1 = 1, lo = std::numeric_limits<double>::infinity(), hi = -lo;
  if (!s.times.empty()) {
    t0 = s.times.front();
    t1 = std::max(s.times.back(), t0 + 1e-3);
  }
  for (const auto& v : s.values)
    for (float x : v)
      if (std::isfinite(x)) {
        lo = std::min(lo, static_cast<double>(x));
        hi = std::max(hi, static_cast<double>(x));
      }
  if (!(lo <= hi)) lo = 0, hi = 1;
  if (hi - lo < 1e-9) lo -= 0.5, hi += 0.5;
  const double pad = 0.05 * (hi - lo);
  lo -= pad;
  hi += pad;
  const double pw = kWidth - kLeft - kRight, ph = kHeight - kTop - kBottom;
  const auto px = [&](double t) { return kLeft + (t - t0) / (t1 - t0) * pw; };
  const auto py = [&](double v) { return kTop + (hi - v) / (hi - lo) * ph; };
  char buf[256];

  out << svg_plot_open(kWidth, kHeight);
  out << "<text x=\"" << kLeft << "\" y=\"22\" font-size=\"14\" fill=\"#222\">"
      << svg_escape(s.robot + " / " + s.task + " / " + s.channel) << " (" << s.samples << " samples)</text>\n";
  // Grid and ticks.
  out << "<g stroke=\"#ddd\" fill=\"#444\">\n";
  const double vstep = svg_tick_step(hi - lo, 5);
  for (double v = std::ceil(lo / vstep) * vstep; v <= hi; v += vstep) {
    std::snprintf(buf, sizeof buf, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>", kLeft, py(v), kLeft + pw,
                  py(v));
    out << buf;
    std::snprintf(buf, sizeof buf, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\" stroke=\"none\">", kLeft - 6,
                  py(v) + 4);
    out << buf << svg_number(v) << "</text>\n";
  }
  const double tstep = svg_tick_step(t1 - t0, 8);
  for (double t = std::ceil(t0 / tstep) * tstep; t <= t1; t += tstep) {
    std::snprintf(buf, sizeof buf, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>", px(t), kTop, px(t),
                  kTop + ph);
    out << buf;
    std::snprintf(buf, sizeof buf, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" stroke=\"none\">", px(t),
                  kTop + ph + 16);
    out << buf << svg_number(t) << "</text>\n";
  }
  out << "</g>\n";
  std::snprintf(buf, sizeof buf,
                "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" stroke=\"#333\"/>\n"
                "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" fill=\"#444\">time (s)</text>\n",
                kLeft, kTop, pw, ph, kLeft + pw / 2, kHeight - 8);
  out << buf;
  // One polyline per value index; a NaN (a shorter sample) breaks the line.
  out << "<g fill=\"none\" stroke-width=\"1.5\" stroke-linejoin=\"round\">\n";
  for (std::size_t k = 0; k < s.width; ++k) {
    const std::string c = svg_colour(k);
    bool open = false;
    for (std::size_t i = 0; i < s.times.size(); ++i) {
      const bool have = k < s.values[i].size() && std::isfinite(s.values[i][k]);
      if (!have) {
        if (open) out << "\"/>\n";
        open = false;
        continue;
      }
      if (!open) {
        out << "<polyline stroke=\"" << c << "\" points=\"";
        open = true;
      }
      std::snprintf(buf, sizeof buf, "%.1f,%.1f ", px(s.times[i]), py(s.values[i][k]));
      out << buf;
    }
    if (open) out << "\"/>\n";
  }
  out << "</g>\n";
  // Legend: value indices.
  for (std::size_t k = 0; k < std::min(s.width, kMaxLegend); ++k) {
    const double y = kTop + 8 + 16 * static_cast<double>(k);
    std::snprintf(buf, sizeof buf,
                  "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"%s\" stroke-width=\"3\"/>"
                  "<text x=\"%.1f\" y=\"%.1f\" fill=\"#222\">",
                  kLeft + pw + 12, y, kLeft + pw + 32, y, svg_colour(k).c_str(), kLeft + pw + 38, y + 4);
    out << buf << svg_escape(s.channel) << "[" << k << "]</text>\n";
  }
  if (s.width > kMaxLegend) {
    std::snprintf(buf, sizeof buf, "<text x=\"%.1f\" y=\"%.1f\" fill=\"#222\">", kLeft + pw + 12,
                  kTop + 8 + 16 * static_cast<double>(kMaxLegend) + 4);
    out << buf << "+" << s.width - kMaxLegend << " more</text>\n";
  }
  out << "</svg>\n";
}

}  // namespace symb::apps::run
