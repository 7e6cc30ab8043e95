// Fuzzes the parameter parsers that turn shell, scenario and genome text into typed values: the
// assignment splitter and each type's value parser. Any input must give a value or an error,
// never a crash, and every accepted value must read back from its own canonical text.
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "symb/os/param.hpp"

using namespace symb::os;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  static const ParamSpec specs[] = {
      {"b", ParamType::kBool, false, {}, {}, ""},
      {"i", ParamType::kInt, std::int64_t{0}, -1e6, 1e6, ""},
      {"r", ParamType::kReal, 0.0, {}, {}, ""},
      {"d", ParamType::kDuration, symb::kernel::Duration{0}, 0.0, 3600.0, ""},
      {"s", ParamType::kString, std::string(), {}, 64.0, ""},
  };
  auto list = parse_param_assignments(text);
  if (list) {
    for (const auto& a : *list) {
      if (!is_valid_name(a.name) || a.column == 0 || a.column > size) std::abort();
      for (const auto& spec : specs) {
        auto v = parse_param_value(spec, a.value);
        if (!v) continue;
        auto back = parse_param_value(spec, format_param_value(*v));
        if (!back || !(*back == *v)) std::abort();
      }
    }
  }
  for (const auto& spec : specs) (void)parse_param_value(spec, text);
  return 0;
}
