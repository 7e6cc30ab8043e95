// A scenario the project ships (scenarios/), parsed as `symb run` parses it: what the simulation
// tests start from. A file that does not parse fails the test that asked for it, with the
// parser's message, and gives an empty scenario.
#pragma once

#include <string>

#include <gtest/gtest.h>

#include "symb/sim/scenario.hpp"

namespace symb::sim::test {

inline Scenario load_shipped(const std::string& name) {
  auto s = load_scenario(std::string(SYMB_SCENARIO_DIR) + "/" + name);
  EXPECT_TRUE(s.ok()) << (s ? "" : s.error());
  return s ? std::move(s).value() : Scenario{};
}

}  // namespace symb::sim::test
