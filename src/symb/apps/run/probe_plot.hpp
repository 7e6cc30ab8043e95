// Probe plots: one SVG line chart per probe series (a robot's task's channel over time), one line
// per value index, with axes, ticks and a legend, for a person to look at after a run (hormone
// levels rising and decaying, activations, which layer was active).
#pragma once

#include <ostream>

#include "symb/apps/run/probe_recorder.hpp"

namespace symb::apps::run {

void write_probe_svg(std::ostream& out, const ProbeSeries& series);

// A file name for the series: "<robot>.<task>.<channel>.svg" with anything but [A-Za-z0-9_.-]
// made '_'.
std::string probe_file_name(const ProbeSeries& series);

}  // namespace symb::apps::run
