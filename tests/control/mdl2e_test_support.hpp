// Helpers for the MDL2e tests: compile or fail the test, times in milliseconds, and a compact
// text form of a step's events for golden comparisons.
#pragma once

#include <chrono>
#include <string>
#include <string_view>

#include <gtest/gtest.h>

#include "symb/control/mdl2e/compiler.hpp"
#include "symb/control/mdl2e/interpreter.hpp"

#include "support/virtual_time.hpp"

namespace symb::control::mdl2e::testing {

using test_support::ms;

inline Program must_compile(std::string_view source) {
  auto p = compile_source(source);
  EXPECT_TRUE(p.ok()) << (p.ok() ? std::string() : p.error());
  return p.ok() ? std::move(p).value() : Program{};
}

// "started:plan started:a interrupted:a ..." for the events of one step.
inline std::string events(const Output& out) {
  std::string s;
  for (const Event& e : out.event_list()) {
    if (!s.empty()) s += ' ';
    s += std::string(event_kind_name(e.kind)) + ":" + std::string(e.name);
    if (e.kind == EventKind::kTaskAction) s += "/" + std::string(task_action_name(e.task_action));
  }
  return s;
}

// "forward(100)" or "stop" or "ended".
inline std::string atom(const Output& out) {
  if (!out.running) return "ended";
  if (out.atom == kNoIndex) return "none";
  std::string s(out.primitive_name);
  if (out.param_count) {
    s += '(';
    for (std::size_t k = 0; k < out.param_count; ++k) {
      if (k) s += ',';
      s += std::to_string(static_cast<long long>(out.params[k]));
    }
    s += ')';
  }
  return s;
}

}  // namespace symb::control::mdl2e::testing
