#include "symb/os/param.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace symb::os {

using kernel::Error;
using kernel::Result;
using kernel::Status;

const char* to_string(ParamType t) {
  switch (t) {
    case ParamType::kBool: return "bool";
    case ParamType::kInt: return "int";
    case ParamType::kReal: return "real";
    case ParamType::kDuration: return "duration";
    case ParamType::kString: return "string";
  }
  return "?";
}

ParamType type_of(const ParamValue& v) { return static_cast<ParamType>(v.index()); }

namespace {

std::string format_real(double d) {
  // Shortest text that reads back to the same double.
  char buf[64];
  auto r = std::to_chars(buf, buf + sizeof buf, d);
  return {buf, r.ptr};
}

std::string format_duration(kernel::Duration d) {
  const std::int64_t ns = d.count();
  if (ns % 1'000'000'000 == 0) return std::to_string(ns / 1'000'000'000) + "s";
  if (ns % 1'000'000 == 0) return std::to_string(ns / 1'000'000) + "ms";
  if (ns % 1'000 == 0) return std::to_string(ns / 1'000) + "us";
  return std::to_string(ns) + "ns";
}

std::string shorten(std::string_view text) {
  std::string s(text.substr(0, 40));
  for (char& c : s)
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = '?';
  if (text.size() > 40) s += "...";
  return s;
}

Error bad_value(const ParamSpec& spec, std::string_view text, const char* expected) {
  return Error{"parameter '" + spec.name + "': expected " + expected + ", got '" + shorten(text) + "'"};
}

std::optional<double> parse_double(std::string_view text) {
  double d = 0;
  if (text.empty() || text.front() == '+') return std::nullopt;
  auto r = std::from_chars(text.data(), text.data() + text.size(), d);
  if (r.ec != std::errc{} || r.ptr != text.data() + text.size() || !std::isfinite(d)) return std::nullopt;
  return d;
}

}  // namespace

Result<kernel::Duration> parse_duration(std::string_view text) {
  std::size_t unit_at = text.size();
  while (unit_at > 0 && std::isalpha(static_cast<unsigned char>(text[unit_at - 1]))) --unit_at;
  const std::string_view unit = text.substr(unit_at);
  double scale = 0;
  if (unit == "ns")
    scale = 1;
  else if (unit == "us")
    scale = 1e3;
  else if (unit == "ms")
    scale = 1e6;
  else if (unit == "s")
    scale = 1e9;
  else if (unit == "min")
    scale = 60e9;
  else if (unit == "h")
    scale = 3600e9;
  else
    return Error{"'" + shorten(text) + "' has no unit: write e.g. 30ms, 1.5s, 250us, 2min"};
  auto d = parse_double(text.substr(0, unit_at));
  if (!d || *d < 0) return Error{"'" + shorten(text) + "' is not a non-negative duration"};
  if (*d * scale > 9.2e18) return Error{"'" + shorten(text) + "' is too long a duration"};
  return kernel::Duration{static_cast<std::int64_t>(std::llround(*d * scale))};
}

std::string format_param_value(const ParamValue& v) {
  switch (type_of(v)) {
    case ParamType::kBool: return std::get<bool>(v) ? "true" : "false";
    case ParamType::kInt: return std::to_string(std::get<std::int64_t>(v));
    case ParamType::kReal: return format_real(std::get<double>(v));
    case ParamType::kDuration: return format_duration(std::get<kernel::Duration>(v));
    case ParamType::kString: return std::get<std::string>(v);
  }
  return {};
}

Status check_param_value(const ParamSpec& spec, const ParamValue& v) {
  if (type_of(v) != spec.type)
    return Error{"parameter '" + spec.name + "': expected " + to_string(spec.type) + ", got " + to_string(type_of(v))};
  double magnitude = 0;
  const char* what = "value";
  switch (spec.type) {
    case ParamType::kBool: return {};
    case ParamType::kInt: magnitude = static_cast<double>(std::get<std::int64_t>(v)); break;
    case ParamType::kReal: magnitude = std::get<double>(v); break;
    case ParamType::kDuration:
      magnitude = kernel::to_seconds(std::get<kernel::Duration>(v));
      what = "duration (s)";
      break;
    case ParamType::kString:
      magnitude = static_cast<double>(std::get<std::string>(v).size());
      what = "length";
      break;
  }
  if ((spec.min && magnitude < *spec.min) || (spec.max && magnitude > *spec.max)) {
    std::string range = "[" + (spec.min ? format_real(*spec.min) : std::string("-inf")) + ", " +
                        (spec.max ? format_real(*spec.max) : std::string("inf")) + "]";
    return Error{"parameter '" + spec.name + "': " + what + " " + format_real(magnitude) + " is outside " + range};
  }
  return {};
}

Result<ParamValue> parse_param_value(const ParamSpec& spec, std::string_view text) {
  ParamValue v;
  switch (spec.type) {
    case ParamType::kBool: {
      if (text == "true" || text == "1" || text == "yes" || text == "on")
        v = true;
      else if (text == "false" || text == "0" || text == "no" || text == "off")
        v = false;
      else
        return bad_value(spec, text, "true or false");
      break;
    }
    case ParamType::kInt: {
      std::int64_t i = 0;
      auto r = std::from_chars(text.data(), text.data() + text.size(), i);
      if (text.empty() || r.ec != std::errc{} || r.ptr != text.data() + text.size())
        return bad_value(spec, text, "an integer");
      v = i;
      break;
    }
    case ParamType::kReal: {
      auto d = parse_double(text);
      if (!d) return bad_value(spec, text, "a finite real number");
      v = *d;
      break;
    }
    case ParamType::kDuration: {
      auto d = parse_duration(text);
      if (!d) return bad_value(spec, text, "a non-negative duration with a unit (ns, us, ms, s, min, h) such as 30ms");
      v = *d;
      break;
    }
    case ParamType::kString: v = std::string(text); break;
  }
  if (auto st = check_param_value(spec, v); !st) return Error{st.error()};
  return v;
}

Result<std::vector<ParamAssignment>> parse_param_assignments(std::string_view text) {
  std::vector<ParamAssignment> out;
  std::size_t i = 0;
  const auto col = [&](std::size_t at) { return std::to_string(at + 1); };
  while (true) {
    while (i < text.size() && (text[i] == ' ' || text[i] == '\t')) ++i;
    if (i >= text.size()) break;
    ParamAssignment a;
    a.column = i + 1;
    const std::size_t name_start = i;
    while (i < text.size() && text[i] != '=' && text[i] != ' ' && text[i] != '\t') ++i;
    a.name = std::string(text.substr(name_start, i - name_start));
    if (i >= text.size() || text[i] != '=')
      return Error{"column " + col(name_start) + ": expected name=value, got '" + shorten(a.name) + "'"};
    if (!is_valid_name(a.name))
      return Error{"column " + col(name_start) + ": '" + shorten(a.name) + "' is not a valid parameter name"};
    ++i;  // '='
    if (i < text.size() && text[i] == '"') {
      const std::size_t quote = i++;
      bool closed = false;
      while (i < text.size()) {
        char c = text[i++];
        if (c == '"') {
          closed = true;
          break;
        }
        if (c == '\\') {
          if (i >= text.size()) break;
          c = text[i++];
          if (c != '"' && c != '\\')
            return Error{"column " + col(i - 2) + ": unknown escape '\\" + shorten({&c, 1}) + "'"};
        }
        a.value.push_back(c);
      }
      if (!closed) return Error{"column " + col(quote) + ": unterminated quoted value"};
      if (i < text.size() && text[i] != ' ' && text[i] != '\t')
        return Error{"column " + col(i) + ": expected a space after the quoted value"};
    } else {
      const std::size_t value_start = i;
      while (i < text.size() && text[i] != ' ' && text[i] != '\t') {
        if (text[i] == '"') return Error{"column " + col(i) + ": a quote may only open a value"};
        ++i;
      }
      a.value = std::string(text.substr(value_start, i - value_start));
    }
    out.push_back(std::move(a));
  }
  return out;
}

const ParamValue* ParamSet::find(std::string_view name) const {
  for (const auto& [n, v] : values_)
    if (n == name) return &v;
  return nullptr;
}

const ParamValue& ParamSet::at(std::string_view name) const {
  if (const ParamValue* v = find(name)) return *v;
  throw std::out_of_range("no parameter '" + std::string(name) + "'");
}

void ParamSet::set(std::string_view name, ParamValue v) {
  for (auto& [n, old] : values_)
    if (n == name) {
      old = std::move(v);
      return;
    }
  values_.emplace_back(std::string(name), std::move(v));
}

bool is_valid_name(std::string_view name) {
  if (name.empty() || name.size() > 63) return false;
  const auto c0 = static_cast<unsigned char>(name.front());
  if (!std::isalpha(c0) && c0 != '_') return false;
  return std::all_of(name.begin(), name.end(), [](char ch) {
    const auto c = static_cast<unsigned char>(ch);
    return std::isalnum(c) || c == '_' || c == '.' || c == '-';
  });
}

std::string closest_name(std::string_view name, std::span<const std::string_view> candidates) {
  // Edit distance counting a swap of two neighbours as one edit (typing errors are mostly
  // those); a hint only when at most about a third of the letters differ.
  std::string best;
  std::size_t best_d = std::max<std::size_t>(1, name.size() / 3) + 1;
  for (std::string_view c : candidates) {
    const std::size_t w = c.size() + 1;
    std::vector<std::size_t> d((name.size() + 1) * w);
    for (std::size_t j = 0; j < w; ++j) d[j] = j;
    for (std::size_t i = 1; i <= name.size(); ++i) {
      d[i * w] = i;
      for (std::size_t j = 1; j <= c.size(); ++j) {
        std::size_t v = std::min(
            {d[(i - 1) * w + j] + 1, d[i * w + j - 1] + 1, d[(i - 1) * w + j - 1] + (name[i - 1] == c[j - 1] ? 0 : 1)});
        if (i > 1 && j > 1 && name[i - 1] == c[j - 2] && name[i - 2] == c[j - 1])
          v = std::min(v, d[(i - 2) * w + j - 2] + 1);
        d[i * w + j] = v;
      }
    }
    if (d.back() < best_d) {
      best_d = d.back();
      best = std::string(c);
    }
  }
  return best;
}

}  // namespace symb::os
