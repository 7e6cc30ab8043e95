#include "symb/apps/run/steps_csv.hpp"

#include <algorithm>
#include <charconv>

namespace symb::apps::run {

std::string steps_csv_header() {
  std::string s = "time_s,robot,x_cm,y_cm,heading_rad";
  for (std::size_t k = 0; k < sim::kIrCount; ++k) s += ",ir" + std::to_string(k);
  return s + ",left_cm_s,right_cm_s,contact\n";
}

void append_fixed(std::string& out, double v, int decimals) {
  // Room for any double in fixed notation (309 digits before the point) and up to 60 after it.
  char buf[400];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed, std::clamp(decimals, 0, 60));
  if (ec == std::errc{}) out.append(buf, end);
}

void append_steps_csv_row(std::string& out, double time_s, std::string_view robot, const sim::RobotStep& step) {
  const sim::RobotState& s = step.state;
  append_fixed(out, time_s, 3);
  out += ',';
  out += robot;
  out += ',';
  append_fixed(out, s.pose.x, 3);
  out += ',';
  append_fixed(out, s.pose.y, 3);
  out += ',';
  append_fixed(out, s.pose.theta, 4);
  for (float v : step.ir) {
    out += ',';
    append_fixed(out, static_cast<double>(v), 1);
  }
  out += ',';
  append_fixed(out, s.left_speed, 3);
  out += ',';
  append_fixed(out, s.right_speed, 3);
  out += s.in_contact ? ",1\n" : ",0\n";
}

}  // namespace symb::apps::run
