// Parameters: the typed, documented knobs of a task type. A ParamSpec is the schema entry (name,
// type, default, range, doc); a ParamSet is one task's resolved values. Values arrive as text
// from the shell, scenario files and genomes, so parsing lives here, once, with errors that say
// which parameter and which column was wrong.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"

namespace symb::os {

enum class ParamType { kBool, kInt, kReal, kDuration, kString };

using ParamValue = std::variant<bool, std::int64_t, double, kernel::Duration, std::string>;

struct ParamSpec {
  std::string name;
  ParamType type = ParamType::kReal;
  ParamValue default_value = 0.0;
  // Inclusive bounds for numbers; for durations in seconds; for strings on the length.
  std::optional<double> min;
  std::optional<double> max;
  std::string doc;
};

const char* to_string(ParamType t);
ParamType type_of(const ParamValue& v);
// The canonical text of a value; parse_param_value() reads it back to the same value.
std::string format_param_value(const ParamValue& v);
// Parses a duration with its unit: "30ms", "1.5s", "250us", "100ns", "2min", "1h".
kernel::Result<kernel::Duration> parse_duration(std::string_view text);
// Parses `text` as a value of `spec`'s type and checks its range.
kernel::Result<ParamValue> parse_param_value(const ParamSpec& spec, std::string_view text);
// Checks a value's type and range against `spec` (error names the parameter).
kernel::Status check_param_value(const ParamSpec& spec, const ParamValue& v);

// One `name=value` of a parameter list, with the column (1-based) where it started.
struct ParamAssignment {
  std::string name;
  std::string value;
  std::size_t column = 1;
};

// Splits `a=1 b=2.5 c="two words"` into assignments. Values may be double-quoted (with \" and
// \\ escapes). Errors give the column.
kernel::Result<std::vector<ParamAssignment>> parse_param_assignments(std::string_view text);

// One task's resolved parameters, in schema order.
class ParamSet {
 public:
  ParamSet() = default;
  explicit ParamSet(std::vector<std::pair<std::string, ParamValue>> values) : values_(std::move(values)) {}

  const ParamValue* find(std::string_view name) const;
  // Typed getters; the value must exist with that type (the schema guarantees it).
  bool boolean(std::string_view name) const { return std::get<bool>(at(name)); }
  std::int64_t integer(std::string_view name) const { return std::get<std::int64_t>(at(name)); }
  double real(std::string_view name) const { return std::get<double>(at(name)); }
  kernel::Duration duration(std::string_view name) const { return std::get<kernel::Duration>(at(name)); }
  const std::string& string(std::string_view name) const { return std::get<std::string>(at(name)); }

  void set(std::string_view name, ParamValue v);
  const std::vector<std::pair<std::string, ParamValue>>& values() const { return values_; }

 private:
  const ParamValue& at(std::string_view name) const;
  std::vector<std::pair<std::string, ParamValue>> values_;
};

// Whether `name` may name a task, a task type or a parameter: 1 to 63 of [A-Za-z0-9_.-],
// starting with a letter or '_'.
bool is_valid_name(std::string_view name);
// The closest of `candidates` to `name`, for "did you mean" hints; empty when none is close.
std::string closest_name(std::string_view name, std::span<const std::string_view> candidates);

}  // namespace symb::os
