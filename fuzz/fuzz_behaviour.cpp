// Fuzzes the behaviour family's one text parser, the waypoint list ("x1,y1;x2,y2;...") that
// move_to_goal's `via` and stay_on_path's `path` take. Any input must give points or an error
// "waypoint N, column C: message" with C inside the text (or just past its end), never a crash;
// accepted points must be finite, within +-1e6 cm and at most kMaxWaypoints.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "symb/control/schemas/waypoints.hpp"

using namespace symb::control::behaviour;

namespace {

// Reads "waypoint N, column C: " at the start of `e`; false when it is not there.
bool located(const std::string& e, std::size_t text_size) {
  const std::string_view head = "waypoint ";
  if (e.rfind(head, 0) != 0) return false;
  std::size_t i = head.size();
  auto number = [&](std::size_t& out) {
    const std::size_t s = i;
    out = 0;
    while (i < e.size() && e[i] >= '0' && e[i] <= '9' && i - s < 12)
      out = out * 10 + static_cast<std::size_t>(e[i++] - '0');
    return i > s;
  };
  std::size_t n = 0, column = 0;
  if (!number(n) || n == 0 || n > kMaxWaypoints + 1) return false;
  if (e.compare(i, 9, ", column ") != 0) return false;
  i += 9;
  if (!number(column) || column == 0 || column > text_size + 1) return false;
  return e.compare(i, 2, ": ") == 0 && e.size() > i + 2;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto r = parse_waypoints(text);
  if (!r) {
    if (!located(r.error(), size)) std::abort();
    return 0;
  }
  if (r->size() > kMaxWaypoints) std::abort();
  for (const Point& p : *r)
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || std::fabs(p.x) > 1e6 || std::fabs(p.y) > 1e6) std::abort();
  return 0;
}
