// SVG helpers shared by the pictures and plots the tool writes (swarm trajectories, maze runs,
// probe and spike plots): their openings, tick steps and labels, a palette
// of well-separated colours and text escaping. Plain SVG 1.1, nothing that needs a script.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace symb::apps {

// Room below a picture for its caption line, px.
inline constexpr double kSvgCaptionHeight = 28;

// The i-th of a sequence of well-separated hues (golden-angle steps), as #rrggbb.
std::string svg_colour(std::size_t i);
// `text` with &, < and > escaped for an SVG text node.
std::string svg_escape(std::string_view text);

// The opening of a w x h plot (probes, spikes): the XML declaration, the <svg> element in
// sans-serif 12 and a white background. The caller closes it with "</svg>\n".
std::string svg_plot_open(double w, double h);
// The opening of a w x h picture (maze runs, swarm trajectories): as a plot's, without the font.
std::string svg_picture_open(double w, double h);
// A "nice" tick step (1, 2 or 5 times a power of ten) giving about `count` ticks over `span`.
double svg_tick_step(double span, int count);
// A tick label: %g, with values within 1e-12 of 0 shown as 0.
std::string svg_number(double v);

}  // namespace symb::apps
