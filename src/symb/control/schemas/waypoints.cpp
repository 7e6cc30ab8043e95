#include "symb/control/schemas/waypoints.hpp"

#include <cctype>
#include <charconv>
#include <cmath>
#include <string>

namespace symb::control::behaviour {

namespace {

constexpr double kMaxCoordinate = 1e6;

bool is_space(char c) { return c == ' ' || c == '\t'; }

std::string shown(char c) {
  if (std::isprint(static_cast<unsigned char>(c))) return std::string("'") + c + "'";
  return "byte " + std::to_string(static_cast<unsigned>(static_cast<unsigned char>(c)));
}

class Reader {
 public:
  explicit Reader(std::string_view text) : text_(text) {}

  kernel::Result<std::vector<Point>> read() {
    std::vector<Point> points;
    skip_spaces();
    while (i_ < text_.size()) {
      if (points.size() == kMaxWaypoints)
        return fail(points.size() + 1, "more than " + std::to_string(kMaxWaypoints) + " waypoints");
      const std::size_t n = points.size() + 1;
      Point p;
      if (auto st = number(n, "x", p.x); !st) return kernel::Error{st.error()};
      skip_spaces();
      if (i_ >= text_.size()) return fail(n, "expected ',' and then y, got the end of the text");
      if (text_[i_] != ',') return fail(n, "expected ',' between x and y, got " + shown(text_[i_]));
      ++i_;
      skip_spaces();
      if (auto st = number(n, "y", p.y); !st) return kernel::Error{st.error()};
      points.push_back(p);
      skip_spaces();
      if (i_ >= text_.size()) break;
      if (text_[i_] != ';') return fail(n, "expected ';' after the waypoint, got " + shown(text_[i_]));
      ++i_;
      skip_spaces();
    }
    return points;
  }

 private:
  void skip_spaces() {
    while (i_ < text_.size() && is_space(text_[i_])) ++i_;
  }

  kernel::Error fail(std::size_t waypoint, const std::string& what) const {
    return kernel::Error{"waypoint " + std::to_string(waypoint) + ", column " + std::to_string(i_ + 1) + ": " + what};
  }

  kernel::Status number(std::size_t waypoint, const char* which, double& out) {
    if (i_ >= text_.size()) return fail(waypoint, std::string("expected ") + which + ", got the end of the text");
    // from_chars takes no leading '+'; decimal text only (no hex, inf or nan).
    const std::size_t start = i_;
    std::size_t end = i_;
    if (end < text_.size() && (text_[end] == '-' || text_[end] == '+')) ++end;
    while (end < text_.size() &&
           (std::isdigit(static_cast<unsigned char>(text_[end])) || text_[end] == '.' || text_[end] == 'e' ||
            text_[end] == 'E' ||
            ((text_[end] == '-' || text_[end] == '+') && (text_[end - 1] == 'e' || text_[end - 1] == 'E'))))
      ++end;
    std::size_t from = start;
    if (from < end && text_[from] == '+') ++from;
    double v = 0;
    const auto r = std::from_chars(text_.data() + from, text_.data() + end, v, std::chars_format::general);
    if (from == end || r.ec != std::errc() || r.ptr != text_.data() + end) {
      if (r.ptr > text_.data() + from && r.ptr < text_.data() + end)
        i_ = static_cast<std::size_t>(r.ptr - text_.data());
      if (i_ >= text_.size()) return fail(waypoint, std::string("expected ") + which + " (a number), got the end");
      return fail(waypoint, std::string("expected ") + which + " (a number), got " + shown(text_[i_]));
    }
    if (!std::isfinite(v) || std::fabs(v) > kMaxCoordinate)
      return fail(waypoint, std::string(which) + " must be within +-1e6 cm");
    out = v;
    i_ = end;
    return {};
  }

  std::string_view text_;
  std::size_t i_ = 0;
};

}  // namespace

kernel::Result<std::vector<Point>> parse_waypoints(std::string_view text) { return Reader(text).read(); }

}  // namespace symb::control::behaviour
