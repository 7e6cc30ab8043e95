#include "symb/apps/cli_args.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <utility>

#include "symb/os/param.hpp"

namespace symb::apps {

std::string quote_arg(std::string_view text) {
  std::string s = "'";
  for (char ch : text.substr(0, 60)) {
    const auto c = static_cast<unsigned char>(ch);
    s += (c < 0x20 || c == 0x7f) ? '?' : ch;
  }
  if (text.size() > 60) s += "...";
  return s + "'";
}

std::string did_you_mean(std::string_view given, std::span<const std::string_view> candidates) {
  const std::string hint = os::closest_name(given, candidates);
  return hint.empty() ? std::string() : " (did you mean '" + hint + "'?)";
}

std::variant<std::vector<ParsedOption>, UsageError> parse_options(std::span<const std::string_view> args,
                                                                  std::span<const OptionSpec> specs) {
  std::vector<ParsedOption> out;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string_view arg = args[i];
    if (arg == "-h" || arg == "--help") {
      out.push_back({"--help", {}});
      continue;
    }
    if (!arg.starts_with("--") || arg.size() == 2) {
      if (arg.starts_with("-") && arg.size() > 1) return UsageError{"unknown option " + quote_arg(arg)};
      return UsageError{"unexpected argument " + quote_arg(arg)};
    }
    const std::size_t eq = arg.find('=');
    const std::string_view name = arg.substr(0, eq);
    const OptionSpec* spec = nullptr;
    for (const OptionSpec& s : specs)
      if (s.name == name) spec = &s;
    if (spec == nullptr) {
      std::vector<std::string_view> names;
      for (const OptionSpec& s : specs) names.push_back(s.name);
      return UsageError{"unknown option " + quote_arg(name) + did_you_mean(name, names)};
    }
    ParsedOption p{spec->name, {}};
    const auto missing = [&] {
      return UsageError{"option " + std::string(spec->name) + " needs a value (" + std::string(spec->value_name) + ")"};
    };
    if (spec->value_name.empty()) {
      if (eq != std::string_view::npos) return UsageError{"option " + std::string(spec->name) + " takes no value"};
    } else if (eq != std::string_view::npos) {
      p.value = std::string(arg.substr(eq + 1));
    } else {
      // "--nodes --seed 3" means a forgotten value, not a node count of "--seed".
      if (i + 1 >= args.size() || args[i + 1].starts_with("--")) return missing();
      p.value = std::string(args[++i]);
    }
    if (!spec->value_name.empty() && p.value.empty()) return missing();
    out.push_back(std::move(p));
  }
  return out;
}

std::string describe_options(std::span<const OptionSpec> specs) {
  std::string s;
  for (const OptionSpec& spec : specs) {
    std::string head = "  " + std::string(spec.name);
    if (!spec.value_name.empty()) head += " " + std::string(spec.value_name);
    if (head.size() < 20)
      head.resize(20, ' ');
    else
      head += "  ";
    s += head + std::string(spec.help) + "\n";
  }
  return s;
}

std::optional<UsageError> parse_host_port(std::string_view what, std::string_view text, std::string_view whole,
                                          std::string& host, std::uint16_t& port) {
  const auto colon = text.rfind(':');
  if (colon != std::string_view::npos) {
    host = std::string(text.substr(0, colon));
    text = text.substr(colon + 1);
    if (host.empty()) return UsageError{std::string(what) + ": empty host in " + quote_arg(whole)};
  }
  auto p = parse_count(std::string(what) + " port", text, 0, 65535);
  if (auto* e = std::get_if<UsageError>(&p)) return *e;
  port = static_cast<std::uint16_t>(std::get<std::uint64_t>(p));
  return std::nullopt;
}

std::variant<std::uint64_t, UsageError> parse_count(std::string_view what, std::string_view text, std::uint64_t min,
                                                    std::uint64_t max) {
  const std::string range = "a whole number from " + std::to_string(min) + " to " + std::to_string(max);
  std::uint64_t v = 0;
  const bool digits = !text.empty() && text.find_first_not_of("0123456789") == std::string_view::npos;
  if (!digits) return UsageError{std::string(what) + ": " + quote_arg(text) + " is not " + range};
  auto r = std::from_chars(text.data(), text.data() + text.size(), v);
  if (r.ec == std::errc::result_out_of_range || (r.ec == std::errc{} && (v < min || v > max)))
    return UsageError{std::string(what) + ": " + quote_arg(text) + " is out of range: expected " + range};
  if (r.ec != std::errc{} || r.ptr != text.data() + text.size())
    return UsageError{std::string(what) + ": " + quote_arg(text) + " is not " + range};
  return v;
}

std::variant<std::uint64_t, UsageError> parse_u64(std::string_view what, std::string_view text) {
  const bool hex = text.starts_with("0x") || text.starts_with("0X");
  const std::string_view body = hex ? text.substr(2) : text;
  const std::string_view allowed = hex ? "0123456789abcdefABCDEF" : "0123456789";
  const std::string expected = "an unsigned 64-bit integer (decimal, or hexadecimal with 0x)";
  if (body.empty() || body.find_first_not_of(allowed) != std::string_view::npos)
    return UsageError{std::string(what) + ": " + quote_arg(text) + " is not " + expected};
  std::uint64_t v = 0;
  auto r = std::from_chars(body.data(), body.data() + body.size(), v, hex ? 16 : 10);
  if (r.ec == std::errc::result_out_of_range)
    return UsageError{std::string(what) + ": " + quote_arg(text) + " is out of range: expected " + expected};
  if (r.ec != std::errc{} || r.ptr != body.data() + body.size())
    return UsageError{std::string(what) + ": " + quote_arg(text) + " is not " + expected};
  return v;
}

std::variant<kernel::Duration, UsageError> parse_duration(std::string_view what, std::string_view text,
                                                          kernel::Duration max) {
  const std::string expected = "a duration with a unit, such as 60s, 500ms or 2min";
  auto d = os::parse_duration(text);
  if (!d) return UsageError{std::string(what) + ": " + quote_arg(text) + " is not " + expected};
  if (d->count() < 1 || *d > max)
    return UsageError{std::string(what) + ": " + quote_arg(text) +
                      " is out of range: expected more than 0 and at most " +
                      std::to_string(std::chrono::duration_cast<std::chrono::hours>(max).count()) + "h"};
  return *d;
}

std::variant<double, UsageError> parse_speed(std::string_view what, std::string_view text) {
  const std::string copy(text);
  char* end = nullptr;
  const double v = std::strtod(copy.c_str(), &end);
  if (copy.empty() || end != copy.c_str() + copy.size() || !std::isfinite(v) || v <= 0 || v > 1e6)
    return UsageError{std::string(what) + ": expected a number above 0 and at most 1e6, not " + quote_arg(text)};
  return v;
}

std::variant<double, UsageError> parse_fraction(std::string_view what, std::string_view text) {
  const std::string copy(text);
  char* end = nullptr;
  const double v = std::strtod(copy.c_str(), &end);
  if (copy.empty() || end != copy.c_str() + copy.size() || !(v >= 0 && v <= 1))
    return UsageError{std::string(what) + ": expected a fraction in [0, 1], not " + quote_arg(text)};
  return v;
}

int usage_error(const CliContext& ctx, std::string_view command, const UsageError& e) {
  ctx.err << command << ": " << e.message << "\n(run '" << command << " --help' for usage)\n";
  return kExitUsage;
}

std::variant<SplitArgs, UsageError> split_args(std::span<const std::string_view> args,
                                               std::span<const OptionSpec> specs, std::size_t max_positional) {
  SplitArgs out;
  std::vector<std::string_view> rest;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string_view a = args[i];
    if (a.starts_with("-") && a.size() > 1) {
      rest.push_back(a);
      const bool has_value = a.find('=') == std::string_view::npos &&
                             std::any_of(specs.begin(), specs.end(),
                                         [&](const OptionSpec& s) { return s.name == a && !s.value_name.empty(); });
      if (has_value && i + 1 < args.size()) rest.push_back(args[++i]);
    } else {
      out.positional.push_back(a);
    }
  }
  auto parsed = parse_options(rest, specs);
  if (auto* e = std::get_if<UsageError>(&parsed)) return *e;
  out.options = std::get<std::vector<ParsedOption>>(parsed);
  for (const ParsedOption& o : out.options)
    if (o.name == "--help") out.help = true;
  if (!out.help && out.positional.size() > max_positional)
    return UsageError{"unexpected argument " + quote_arg(out.positional[max_positional])};
  return out;
}

std::variant<SplitArgs, int> scenario_command_args(std::span<const std::string_view> args,
                                                   std::span<const OptionSpec> specs, const CliContext& ctx,
                                                   std::string_view command, void (*print_help)(std::ostream&)) {
  auto split = split_args(args, specs, 1);
  if (auto* e = std::get_if<UsageError>(&split)) return usage_error(ctx, command, *e);
  SplitArgs& a = std::get<SplitArgs>(split);
  if (a.help) {
    print_help(ctx.out);
    return kExitOk;
  }
  if (a.positional.empty()) return usage_error(ctx, command, UsageError{"missing SCENARIO (a .yaml file)"});
  return std::move(a);
}

std::string fixed(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

std::string hex64(std::uint64_t v) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

}  // namespace symb::apps
