#include "symb/apps/run/spike_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <string>
#include <vector>

#include "symb/apps/svg.hpp"
#include "symb/control/snn/izhikevich.hpp"

namespace symb::apps::run {

namespace {

using control::snn::GrownNetwork;
using control::snn::NeuronClass;

// Class colours chosen away from the synapses' blue and red and the channels' green and orange.
constexpr const char* kClassColour[] = {"#e6c229", "#8c6bb1", "#c51b7d", "#35b5a6", "#f4a6c8", "#8c564b", "#b8b8b8"};
static_assert(std::size(kClassColour) == control::snn::kNeuronClassCount);

std::string class_colour(NeuronClass c) {
  const auto i = static_cast<std::size_t>(c);
  return i < std::size(kClassColour) ? kClassColour[i] : "#666666";
}

constexpr const char* kExcitatory = "#2b6cc4";
constexpr const char* kInhibitory = "#d33a2c";
constexpr const char* kInput = "#1a9850";
constexpr const char* kOutput = "#e08214";

}  // namespace

std::string raster_svg(std::span<const SpikeDot> spikes, std::size_t neurons, std::string_view title) {
  constexpr double kWidth = 900, kHeight = 420;
  constexpr double kLeft = 70, kRight = 30, kTop = 36, kBottom = 44;
  std::size_t finite = 0;
  double t0 = 0, t1 = 0;
  std::size_t rows = std::max<std::size_t>(neurons, 1);
  for (const SpikeDot& s : spikes) {
    if (!std::isfinite(s.time_s)) continue;
    ++finite;
    t0 = std::min(t0, s.time_s);
    t1 = std::max(t1, s.time_s);
    rows = std::max<std::size_t>(rows, std::size_t{s.neuron} + 1);
  }
  if (t1 - t0 < 1e-3) t1 = t0 + 1e-3;
  const std::size_t step = finite > kMaxRasterDots ? (finite + kMaxRasterDots - 1) / kMaxRasterDots : 1;
  const double pw = kWidth - kLeft - kRight, ph = kHeight - kTop - kBottom;
  const double row_h = ph / static_cast<double>(rows);
  const double r = std::clamp(0.4 * row_h, 0.6, 2.5);
  const auto px = [&](double t) { return kLeft + (t - t0) / (t1 - t0) * pw; };
  const auto py = [&](double n) { return kTop + ph - (n + 0.5) * row_h; };
  char buf[256];

  std::string out;
  out.reserve(4096 + 40 * std::min(finite, kMaxRasterDots));
  out += svg_plot_open(kWidth, kHeight);
  out += "<text x=\"" + svg_number(kLeft) + "\" y=\"22\" font-size=\"14\" fill=\"#222\">" + svg_escape(title) + " (" +
         std::to_string(finite) + " spikes";
  if (step > 1) out += ", thinned: 1 in " + std::to_string(step) + " shown";
  out += ")</text>\n";
  // Grid and ticks.
  out += "<g stroke=\"#ddd\" fill=\"#444\">\n";
  const double nstep = std::max(1.0, svg_tick_step(static_cast<double>(rows), 6));
  for (double n = 0; n < static_cast<double>(rows); n += nstep) {
    std::snprintf(buf, sizeof buf,
                  "<path d=\"M%.1f %.1fH%.1f\"/><text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\" stroke=\"none\">",
                  kLeft, py(n), kLeft + pw, kLeft - 6, py(n) + 4);
    out += buf + svg_number(n) + "</text>\n";
  }
  const double tstep = svg_tick_step(t1 - t0, 8);
  for (double t = std::ceil(t0 / tstep) * tstep; t <= t1; t += tstep) {
    std::snprintf(buf, sizeof buf,
                  "<path d=\"M%.1f %.1fV%.1f\"/><text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" stroke=\"none\">",
                  px(t), kTop, kTop + ph, px(t), kTop + ph + 16);
    out += buf + svg_number(t) + "</text>\n";
  }
  out += "</g>\n";
  std::snprintf(
      buf, sizeof buf,
      "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" stroke=\"#333\"/>\n"
      "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" fill=\"#444\">time (s)</text>\n"
      "<text transform=\"translate(16 %.1f) rotate(-90)\" text-anchor=\"middle\" fill=\"#444\">neuron</text>\n",
      kLeft, kTop, pw, ph, kLeft + pw / 2, kHeight - 8, kTop + ph / 2);
  out += buf;
  // The dots: one shared fill, so each is only its centre.
  out += "<g fill=\"#111\" stroke=\"none\">\n";
  std::size_t k = 0;
  for (const SpikeDot& s : spikes) {
    if (!std::isfinite(s.time_s)) continue;
    if (k++ % step != 0) continue;
    std::snprintf(buf, sizeof buf, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"%.2g\"/>\n", px(s.time_s),
                  py(static_cast<double>(s.neuron)), r);
    out += buf;
  }
  out += "</g>\n</svg>\n";
  return out;
}

std::string network_svg(const GrownNetwork& net, std::string_view title) {
  const std::size_t n = net.spec.neurons.size();
  // Sites: the grid as stated, grown to hold every neuron that sits outside it.
  int gw = std::max(net.width, 1), gh = std::max(net.height, 1);
  const auto placed = [&](std::size_t i) {
    return i < net.x.size() && i < net.y.size() && net.x[i] >= 0 && net.y[i] >= 0 && net.x[i] < 100000 &&
           net.y[i] < 100000;
  };
  for (std::size_t i = 0; i < n; ++i)
    if (placed(i)) {
      gw = std::max(gw, net.x[i] + 1);
      gh = std::max(gh, net.y[i] + 1);
    }
  const double cell = std::clamp(std::min(640.0 / gw, 480.0 / gh), 3.0, 48.0);
  constexpr double kLeft = 30, kTop = 60, kLegend = 210;
  const double gw_px = cell * gw, gh_px = cell * gh;
  const double width = kLeft + gw_px + kLegend, height = std::max(kTop + gh_px + 30, kTop + 260);
  const double radius = std::max(1.5, 0.32 * cell);
  const auto cx = [&](std::size_t i) { return kLeft + (net.x[i] + 0.5) * cell; };
  const auto cy = [&](std::size_t i) { return kTop + (net.y[i] + 0.5) * cell; };
  char buf[320];

  std::size_t shown_synapses = 0;
  float max_w = 0;
  for (const auto& s : net.spec.synapses)
    if (s.source < n && s.target < n && placed(s.source) && placed(s.target) && std::isfinite(s.weight)) {
      max_w = std::max(max_w, std::fabs(s.weight));
      ++shown_synapses;
    }
  if (!(max_w > 0)) max_w = 1;

  std::string out;
  out += svg_plot_open(width, height);
  out += "<text x=\"" + svg_number(kLeft) + "\" y=\"22\" font-size=\"14\" fill=\"#222\">" + svg_escape(title) +
         "</text>\n";
  std::snprintf(buf, sizeof buf,
                "<text x=\"%.0f\" y=\"40\" fill=\"#444\">%zu neurons, %zu synapses, %dx%d grid, %zu input and %zu "
                "output channels</text>\n",
                kLeft, n, shown_synapses, gw, gh, net.inputs.size(), net.outputs.size());
  out += buf;
  // Arrow heads, one per sign.
  out += "<defs>\n";
  for (const auto& [id, colour] : {std::pair{"ex", kExcitatory}, std::pair{"in", kInhibitory}}) {
    std::snprintf(buf, sizeof buf,
                  "<marker id=\"%s\" viewBox=\"0 0 8 8\" refX=\"8\" refY=\"4\" markerWidth=\"5\" markerHeight=\"5\" "
                  "orient=\"auto\"><path d=\"M0 0L8 4L0 8z\" fill=\"%s\"/></marker>\n",
                  id, colour);
    out += buf;
  }
  out += "</defs>\n";
  // The grid: its frame and, when sites are big enough to see, the lines between them (one path).
  std::snprintf(buf, sizeof buf,
                "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"#fafafa\" stroke=\"#999\"/>\n",
                kLeft, kTop, gw_px, gh_px);
  out += buf;
  if (cell >= 6) {
    out += "<path stroke=\"#e4e4e4\" fill=\"none\" d=\"";
    for (int i = 1; i < gw; ++i) {
      std::snprintf(buf, sizeof buf, "M%.1f %.1fV%.1f", kLeft + i * cell, kTop, kTop + gh_px);
      out += buf;
    }
    for (int j = 1; j < gh; ++j) {
      std::snprintf(buf, sizeof buf, "M%.1f %.1fH%.1f", kLeft, kTop + j * cell, kLeft + gw_px);
      out += buf;
    }
    out += "\"/>\n";
  }
  // Synapses, under the neurons, ending at the target's rim so the arrow head shows.
  out += "<g fill=\"none\" stroke-opacity=\"0.7\">\n";
  for (const auto& s : net.spec.synapses) {
    if (!(s.source < n && s.target < n && placed(s.source) && placed(s.target) && std::isfinite(s.weight))) continue;
    const double x1 = cx(s.source), y1 = cy(s.source);
    double x2 = cx(s.target), y2 = cy(s.target);
    const double dx = x2 - x1, dy = y2 - y1, len = std::hypot(dx, dy);
    if (len > 2 * radius) {
      x2 -= dx / len * radius;
      y2 -= dy / len * radius;
    } else {  // a self-synapse: a short stub up and to the right
      x2 = x1 + 1.6 * radius;
      y2 = y1 - 1.6 * radius;
    }
    const bool excitatory = s.weight >= 0;
    const double w = 0.5 + 2.5 * std::fabs(s.weight) / max_w;
    std::snprintf(buf, sizeof buf,
                  "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"%s\" stroke-width=\"%.2f\" "
                  "marker-end=\"url(#%s)\"/>\n",
                  x1, y1, x2, y2, excitatory ? kExcitatory : kInhibitory, w, excitatory ? "ex" : "in");
    out += buf;
  }
  out += "</g>\n";
  // Neurons.
  out += "<g stroke=\"#222\" stroke-width=\"0.8\">\n";
  for (std::size_t i = 0; i < n; ++i) {
    if (!placed(i)) continue;
    const NeuronClass c = i < net.classes.size() ? net.classes[i] : NeuronClass::kRS;
    std::snprintf(buf, sizeof buf, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"%.1f\" fill=\"%s\"/>\n", cx(i), cy(i), radius,
                  class_colour(c).c_str());
    out += buf;
  }
  out += "</g>\n";
  // Channels at the neurons they drive (inputs, above) or are read from (outputs, below).
  const double font = std::clamp(0.42 * cell, 7.0, 12.0);
  const auto mark = [&](const std::vector<std::vector<std::uint32_t>>& channels, const char* colour, const char* word,
                        double dy) {
    for (std::size_t ch = 0; ch < channels.size(); ++ch)
      for (std::uint32_t i : channels[ch]) {
        if (i >= n || !placed(i)) continue;
        std::snprintf(buf, sizeof buf,
                      "<text x=\"%.1f\" y=\"%.1f\" font-size=\"%.1f\" text-anchor=\"middle\" fill=\"%s\" "
                      "font-weight=\"bold\">%s %zu</text>\n",
                      cx(i), cy(i) + dy, font, colour, word, ch);
        out += buf;
      }
  };
  mark(net.inputs, kInput, "in", -radius - 2);
  mark(net.outputs, kOutput, "out", radius + font);
  // Legend: classes, synapse signs, channel marks (swatches are rects, so circles stay neurons).
  const double lx = kLeft + gw_px + 20;
  double ly = kTop + 6;
  const auto entry = [&](const std::string& colour, const std::string& text) {
    std::snprintf(buf, sizeof buf,
                  "<rect x=\"%.1f\" y=\"%.1f\" width=\"12\" height=\"12\" fill=\"%s\"/><text x=\"%.1f\" y=\"%.1f\" "
                  "fill=\"#222\">",
                  lx, ly, colour.c_str(), lx + 18, ly + 10);
    out += buf + svg_escape(text) + "</text>\n";
    ly += 18;
  };
  for (int c = 0; c < control::snn::kNeuronClassCount; ++c)
    entry(class_colour(static_cast<NeuronClass>(c)),
          std::string(control::snn::to_string(static_cast<NeuronClass>(c))) + " neuron");
  ly += 6;
  entry(kExcitatory, "excitatory synapse");
  entry(kInhibitory, "inhibitory synapse");
  entry(kInput, "in C: input channel C");
  entry(kOutput, "out C: output channel C");
  out += "</svg>\n";
  return out;
}

}  // namespace symb::apps::run
