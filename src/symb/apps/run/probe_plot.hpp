// Probe plots: one SVG line chart per probe series (a robot's task's channel over time), one line
// per value index, with axes, ticks and a legend, for a person to look at after a run (hormone
// levels rising and decaying, activations, which layer was active).
#pragma once

#include <cstddef>
#include <filesystem>
#include <ostream>
#include <string_view>
#include <vector>

#include "symb/apps/run/probe_recorder.hpp"
#include "symb/kernel/result.hpp"

namespace symb::apps::run {

void write_probe_svg(std::ostream& out, const ProbeSeries& series);

// A file name for the series: "<robot>.<task>.<channel>.svg" with anything but [A-Za-z0-9_.-]
// made '_'.
std::string probe_file_name(const ProbeSeries& series);

// Writes a chart per series into `dir` (made when needed), at most `max_charts`, shared fairly
// among the kinds of series (task and channel) in order of first appearance; the files written.
kernel::Result<std::vector<std::filesystem::path>> write_probe_charts(const std::filesystem::path& dir,
                                                                      const ProbeRecorder& probes,
                                                                      std::size_t max_charts);

// Writes a chart per series into `dir` (made when needed), named by probe_file_name; the files.
kernel::Result<std::vector<std::filesystem::path>> write_charts(const std::filesystem::path& dir,
                                                                const std::vector<const ProbeSeries*>& series);

// Series that set the robots side by side: for each kind (task, channel) whose channel starts
// with `channel_prefix` and each value index k below `max_values`, one series whose line r is
// robot r's value k (robot "modules", channel "<channel>.v<k>", the robots' names as labels).
// An organism's hormone levels per module (channel "hormones/c0", a value per hormone) so form a
// gradient to be seen in one chart.
std::vector<ProbeSeries> module_series(const ProbeRecorder& probes, std::string_view channel_prefix,
                                       std::size_t max_values);

}  // namespace symb::apps::run
