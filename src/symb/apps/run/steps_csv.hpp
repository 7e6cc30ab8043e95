// steps.csv's text: the header and a row per robot and recorded step, written with std::to_chars
// into a caller's buffer (one write per step instead of a printf per number). The text is the one
// printf's "%.3f" / "%.4f" / "%.1f" gave: time_s and x, y, wheel speeds with 3 decimals, the
// heading with 4, the IR readings with 1, contact 0 or 1.
#pragma once

#include <string>
#include <string_view>

#include "symb/sim/world_runner.hpp"

namespace symb::apps::run {

// "time_s,robot,x_cm,y_cm,heading_rad,ir0..ir6,left_cm_s,right_cm_s,contact\n"
std::string steps_csv_header();
// Appends one row (with its newline) to `out`.
void append_steps_csv_row(std::string& out, double time_s, std::string_view robot, const sim::RobotStep& step);
// Appends `v` with `decimals` digits after the point, as printf("%.*f") writes it.
void append_fixed(std::string& out, double v, int decimals);

}  // namespace symb::apps::run
