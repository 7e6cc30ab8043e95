// The AHHS description text (docs/ahhs.md, "Description format"): one statement per line (or
// separated by ';'), '#' starts a comment. Statements, in this order of need (a name or a
// compartment is declared before it is used):
//
//   compartments 2
//   link 0 1
//   hormone obstacle base 0 decay 0.01 diffusion 0.05 [min 0] [max 1] [start 0]
//   sensor 0 in 0                 # sensor vector index 0 sits in compartment 0
//   actuator 1 in 0               # actuator vector index 1 sits in compartment 0
//   rule sensor 0 -> obstacle centre 1 width 1 fixed 1 [dependent 0]
//   rule hormone a -> b centre 0.5 width 0.5 fixed 0.1 dependent -1 [in 1]
//   rule nonlinear a -> b centre ... [in C]
//   rule actuator go -> 1 centre 1 width 1 fixed 1
//
// Every error is "LINE:COLUMN: message", pointing at the token at fault.
#pragma once

#include <string>
#include <string_view>

#include "symb/control/ahhs/network.hpp"
#include "symb/kernel/result.hpp"

namespace symb::control::ahhs {

inline constexpr std::size_t kMaxDescriptionBytes = 4u << 20;

// A validated network, or a located error.
kernel::Result<Network> parse_network(std::string_view text);

// The text of a valid network; parse_network(to_text(n)) gives n back exactly (floats written in
// their shortest exact form).
std::string to_text(const Network& n);

}  // namespace symb::control::ahhs
