#include "symb/sim/playground_world.hpp"

#include <charconv>

#include "symb/sim/ir_model.hpp"

namespace symb::sim {

namespace {

// The shortest text that reads back as the same double.
std::string number(double v) {
  char buf[32];
  auto r = std::to_chars(buf, buf + sizeof buf, v == 0 ? 0.0 : v);
  return std::string(buf, r.ptr);
}

std::string attribute_text(std::string_view s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += (static_cast<unsigned char>(c) < 0x20 ? ' ' : c);
    }
  }
  return out;
}

}  // namespace

kernel::Result<std::string> playground_world(const Scenario& sc, std::uint16_t first_port) {
  if (sc.world_kind != WorldKind::kEnki)
    return kernel::Error{sc.file + ": a 3D world of modules has no Aseba Playground counterpart"};
  if (first_port == 0 || first_port + sc.robots.size() - (sc.robots.empty() ? 0 : 1) > 65535)
    return kernel::Error{"ports " + std::to_string(first_port) + " and up do not fit " +
                         std::to_string(sc.robots.size()) + " robots"};
  const WorldSpec& w = sc.world;
  std::string x = "<!DOCTYPE aseba-playground>\n<aseba-playground>\n";
  x += "  <!-- written by symb from " + attribute_text(sc.file) + " (scenario " + attribute_text(sc.name) +
       "): cm and radians -->\n";
  x += "  <color name=\"wall\" r=\"0.9\" g=\"0.9\" b=\"0.9\"/>\n";
  x += "  <world w=\"" + number(w.width) + "\" h=\"" + number(w.height) + "\" color=\"wall\"/>\n";
  const auto rects = IrModel::walls_of(w);
  // The first four rectangles are the arena's sides: Playground's world has its own.
  for (std::size_t i = 4; i < rects.size(); ++i) {
    const auto& r = rects[i];
    x += "  <wall x=\"" + number(r.cx) + "\" y=\"" + number(r.cy) + "\" l1=\"" + number(2 * r.half_length) +
         "\" l2=\"" + number(2 * r.half_width) + "\" h=\"" + number(w.wall_height) + "\" angle=\"" + number(r.angle) +
         "\" color=\"wall\"/>\n";
  }
  for (std::size_t i = 0; i < sc.robots.size(); ++i) {
    const RobotSpec& r = sc.robots[i];
    x += "  <robot type=\"thymio2\" x=\"" + number(r.start.x) + "\" y=\"" + number(r.start.y) + "\" angle=\"" +
         number(r.start.theta) + "\" port=\"" + std::to_string(first_port + i) + "\" name=\"" + attribute_text(r.name) +
         "\"/>\n";
  }
  x += "</aseba-playground>\n";
  return x;
}

}  // namespace symb::sim
