#include "symb/apps/view/view_request.hpp"

namespace symb::apps::view {

std::variant<ViewRequest, UsageError> parse_view(std::string_view text) {
  ViewRequest r;
  r.on = true;
  if (auto e = parse_host_port("--view", text, text, r.host, r.port)) return *e;
  return r;
}

}  // namespace symb::apps::view
