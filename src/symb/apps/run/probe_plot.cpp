#include "symb/apps/run/probe_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <sstream>
#include <string>

#include "symb/apps/svg.hpp"
#include "symb/apps/text_file.hpp"

namespace symb::apps::run {

namespace {

constexpr double kChartWidth = 900, kChartHeight = 360;
constexpr double kChartLeft = 70, kChartRight = 150, kChartTop = 36, kChartBottom = 44;  // room for axes and legend
constexpr std::size_t kMaxLegend = 16;

// The kinds of series (task and channel) whose channel starts with `channel_prefix`, in order of
// first appearance, each with its robots' series.
std::vector<std::vector<const ProbeSeries*>> series_by_kind(const ProbeRecorder& probes,
                                                            std::string_view channel_prefix) {
  std::vector<std::vector<const ProbeSeries*>> kinds;
  for (const ProbeSeries* s : probes.series()) {
    if (!s->channel.starts_with(channel_prefix)) continue;
    auto same = std::find_if(kinds.begin(), kinds.end(), [s](const auto& k) {
      return k.front()->task == s->task && k.front()->channel == s->channel;
    });
    if (same == kinds.end())
      kinds.push_back({s});
    else
      same->push_back(s);
  }
  return kinds;
}

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
    // Samples put together from several series (write_module_charts) are in time order per line.
    const auto [first, last] = std::minmax_element(s.times.begin(), s.times.end());
    t0 = *first;
    t1 = std::max(*last, t0 + 1e-3);
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
  const double pw = kChartWidth - kChartLeft - kChartRight, ph = kChartHeight - kChartTop - kChartBottom;
  const auto px = [&](double t) { return kChartLeft + (t - t0) / (t1 - t0) * pw; };
  const auto py = [&](double v) { return kChartTop + (hi - v) / (hi - lo) * ph; };
  char buf[256];

  out << svg_plot_open(kChartWidth, kChartHeight);
  out << "<text x=\"" << kChartLeft << "\" y=\"22\" font-size=\"14\" fill=\"#222\">"
      << svg_escape(s.robot + " / " + s.task + " / " + s.channel) << " (" << s.samples << " samples)</text>\n";
  // Grid and ticks.
  out << "<g stroke=\"#ddd\" fill=\"#444\">\n";
  const double vstep = svg_tick_step(hi - lo, 5);
  for (double v = std::ceil(lo / vstep) * vstep; v <= hi; v += vstep) {
    std::snprintf(buf, sizeof buf, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>", kChartLeft, py(v),
                  kChartLeft + pw, py(v));
    out << buf;
    std::snprintf(buf, sizeof buf, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\" stroke=\"none\">", kChartLeft - 6,
                  py(v) + 4);
    out << buf << svg_number(v) << "</text>\n";
  }
  const double tstep = svg_tick_step(t1 - t0, 8);
  for (double t = std::ceil(t0 / tstep) * tstep; t <= t1; t += tstep) {
    std::snprintf(buf, sizeof buf, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"/>", px(t), kChartTop, px(t),
                  kChartTop + ph);
    out << buf;
    std::snprintf(buf, sizeof buf, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" stroke=\"none\">", px(t),
                  kChartTop + ph + 16);
    out << buf << svg_number(t) << "</text>\n";
  }
  out << "</g>\n";
  std::snprintf(buf, sizeof buf,
                "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" stroke=\"#333\"/>\n"
                "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" fill=\"#444\">time (s)</text>\n",
                kChartLeft, kChartTop, pw, ph, kChartLeft + pw / 2, kChartHeight - 8);
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
    const double y = kChartTop + 8 + 16 * static_cast<double>(k);
    std::snprintf(buf, sizeof buf,
                  "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"%s\" stroke-width=\"3\"/>"
                  "<text x=\"%.1f\" y=\"%.1f\" fill=\"#222\">",
                  kChartLeft + pw + 12, y, kChartLeft + pw + 32, y, svg_colour(k).c_str(), kChartLeft + pw + 38, y + 4);
    out << buf
        << (k < s.labels.size() ? svg_escape(s.labels[k]) : svg_escape(s.channel) + "[" + std::to_string(k) + "]")
        << "</text>\n";
  }
  if (s.width > kMaxLegend) {
    std::snprintf(buf, sizeof buf, "<text x=\"%.1f\" y=\"%.1f\" fill=\"#222\">", kChartLeft + pw + 12,
                  kChartTop + 8 + 16 * static_cast<double>(kMaxLegend) + 4);
    out << buf << "+" << s.width - kMaxLegend << " more</text>\n";
  }
  out << "</svg>\n";
}

kernel::Result<std::vector<std::filesystem::path>> write_probe_charts(const std::filesystem::path& dir,
                                                                      const ProbeRecorder& probes,
                                                                      std::size_t max_charts) {
  // A picture per probe series, for the first robots (a swarm would make hundreds). The
  // max_charts pictures are shared fairly among the kinds of series (task and channel), so an
  // evolution task's few probes are not crowded out by its controllers' many.
  const auto kinds = series_by_kind(probes, "");
  const std::size_t per_kind = kinds.empty() ? 0 : std::max<std::size_t>(1, max_charts / kinds.size());
  std::vector<const ProbeSeries*> chosen;
  for (const auto& k : kinds)
    for (std::size_t i = 0; i < k.size() && i < per_kind && chosen.size() < max_charts; ++i) chosen.push_back(k[i]);
  return write_charts(dir, chosen);
}

kernel::Result<std::vector<std::filesystem::path>> write_charts(const std::filesystem::path& dir,
                                                                const std::vector<const ProbeSeries*>& series) {
  std::vector<std::filesystem::path> files;
  for (const ProbeSeries* s : series) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) return kernel::Error{"cannot create " + dir.string() + ": " + ec.message()};
    std::ostringstream plot;
    write_probe_svg(plot, *s);
    const std::filesystem::path file = dir / probe_file_name(*s);
    if (auto st = write_file(file, plot.str()); !st) return kernel::Error{st.error()};
    files.push_back(file);
  }
  return files;
}

std::vector<ProbeSeries> module_series(const ProbeRecorder& probes, std::string_view channel_prefix,
                                       std::size_t max_values) {
  auto kinds = series_by_kind(probes, channel_prefix);
  // An organism whose modules each run one compartment of a network probes "hormones/c0" on one
  // module, "hormones/c1" on the next: kinds of one task, one series each, from different robots,
  // are one kind then (channel "<prefix>*"), so the gradient along the organism is one chart.
  std::vector<std::vector<const ProbeSeries*>> merged;
  for (auto& kind : kinds) {
    auto same_task = std::find_if(merged.begin(), merged.end(), [&](const auto& m) {
      return m.front()->task == kind.front()->task && kind.size() == 1 &&
             std::none_of(m.begin(), m.end(), [&](const ProbeSeries* s) { return s->robot == kind.front()->robot; });
    });
    if (same_task != merged.end() &&
        (same_task->size() == 1 || same_task->front()->channel != same_task->back()->channel))
      same_task->push_back(kind.front());
    else
      merged.push_back(std::move(kind));
  }
  kinds = std::move(merged);
  std::vector<ProbeSeries> out;
  for (const auto& kind : kinds) {
    std::size_t width = 0;
    for (const ProbeSeries* s : kind) width = std::max(width, s->width);
    for (std::size_t k = 0; k < width && k < max_values; ++k) {
      ProbeSeries c;
      c.robot = "modules";
      c.task = kind.front()->task;
      const bool one_channel = std::all_of(kind.begin(), kind.end(),
                                           [&](const ProbeSeries* s) { return s->channel == kind.front()->channel; });
      c.channel = (one_channel ? kind.front()->channel : std::string(channel_prefix) + "*") + ".v" + std::to_string(k);
      c.width = kind.size();
      // One robot's samples after another's: each line is one unbroken run of rows.
      for (std::size_t r = 0; r < kind.size(); ++r) {
        const ProbeSeries& s = *kind[r];
        c.labels.push_back(s.robot);
        c.samples += s.samples;
        for (std::size_t i = 0; i < s.times.size(); ++i) {
          std::vector<float> row(kind.size(), std::numeric_limits<float>::quiet_NaN());
          if (k < s.values[i].size()) row[r] = s.values[i][k];
          c.times.push_back(s.times[i]);
          c.values.push_back(std::move(row));
        }
      }
      out.push_back(std::move(c));
    }
  }
  return out;
}

}  // namespace symb::apps::run
