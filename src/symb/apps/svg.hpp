// SVG helpers shared by the pictures the tool writes (swarm trajectories, maze runs): a palette
// of well-separated colours and text escaping. Plain SVG 1.1, nothing that needs a script.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace symb::apps {

// The i-th of a sequence of well-separated hues (golden-angle steps), as #rrggbb.
std::string svg_colour(std::size_t i);
// `text` with &, < and > escaped for an SVG text node.
std::string svg_escape(std::string_view text);

}  // namespace symb::apps
