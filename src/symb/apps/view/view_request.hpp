// ViewRequest: what `--view [ADDR:]PORT` asks for (symb run, symb evolve), before there is a run
// to show: the address, the robot shown first and the token.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <variant>

#include "symb/apps/cli_args.hpp"

namespace symb::apps::view {

struct ViewRequest {
  bool on = false;
  std::string host = "127.0.0.1";
  std::uint16_t port = 0;  // 0 picks a free port
  std::string robot;       // shown first; empty: the first robot
  std::string token;       // empty makes one up
};

// The value of --view: [ADDR:]PORT.
std::variant<ViewRequest, UsageError> parse_view(std::string_view text);

}  // namespace symb::apps::view
