// Command-line arguments of the `symb` tool: a small option reader and the value parsers its
// commands share. Bad input is a value (a UsageError), never an exception or a crash, and each
// message names the argument that was wrong and, for a misspelt option, the closest real one.
// The tool exits with kExitUsage for any of them.
#pragma once

#include <cstdint>
#include <optional>
#include <ostream>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "symb/kernel/time.hpp"

namespace symb::apps {

inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;        // the command was fine but could not be carried out
inline constexpr int kExitUsage = 2;          // the command line was wrong
inline constexpr int kExitInterrupted = 130;  // stopped early by Ctrl-C (128 + SIGINT), results written

struct UsageError {
  std::string message;
};

struct OptionSpec {
  std::string_view name;        // "--nodes"
  std::string_view value_name;  // "N"; empty for a flag
  std::string_view help;
};

struct ParsedOption {
  std::string_view name;  // the spec's name
  std::string value;      // empty for a flag
};

// Reads `args` (what follows the command's name) as options of `specs`, as `--name value` or
// `--name=value`. "-h" and "--help" are recognised as "--help" whether or not a spec lists it.
// Positional arguments are refused.
std::variant<std::vector<ParsedOption>, UsageError> parse_options(std::span<const std::string_view> args,
                                                                  std::span<const OptionSpec> specs);

struct SplitArgs {
  std::vector<ParsedOption> options;
  std::vector<std::string_view> positional;
  bool help = false;
};

// Options of `specs` anywhere, positional arguments (up to `max_positional`) anywhere else.
std::variant<SplitArgs, UsageError> split_args(std::span<const std::string_view> args,
                                               std::span<const OptionSpec> specs, std::size_t max_positional);

// Where a command writes: results on `out`, progress and errors on `err`.
struct CliContext {
  std::ostream& out;
  std::ostream& err;
  bool err_is_terminal = false;  // progress lines redraw in place only on a terminal
};

// The arguments of a command `COMMAND SCENARIO [options]`: the split, or the exit status when the
// command is answered already (its help printed, or the usage error reported).
std::variant<SplitArgs, int> scenario_command_args(std::span<const std::string_view> args,
                                                   std::span<const OptionSpec> specs, const CliContext& ctx,
                                                   std::string_view command, void (*print_help)(std::ostream&));

// "  --nodes N      how many robots" lines for a help text.
std::string describe_options(std::span<const OptionSpec> specs);

// Value parsers; `what` names the option in the message ("--nodes").
std::variant<std::uint64_t, UsageError> parse_count(std::string_view what, std::string_view text, std::uint64_t min,
                                                    std::uint64_t max);
// Decimal, or hexadecimal with 0x.
std::variant<std::uint64_t, UsageError> parse_u64(std::string_view what, std::string_view text);
// A number with a unit: ns, us, ms, s, min, h (e.g. 60s, 500ms, 1.5min); within (0, max].
std::variant<kernel::Duration, UsageError> parse_duration(std::string_view what, std::string_view text,
                                                          kernel::Duration max);
// A virtual-time pace (--speed): a number above 0 and at most 1e6.
std::variant<double, UsageError> parse_speed(std::string_view what, std::string_view text);
// [HOST:]PORT (--shell tcp:..., --view): sets `host` when one is given and `port`; an error names
// `what` and quotes `whole`, the option's whole value.
std::optional<UsageError> parse_host_port(std::string_view what, std::string_view text, std::string_view whole,
                                          std::string& host, std::uint16_t& port);
// A fraction in [0, 1].
std::variant<double, UsageError> parse_fraction(std::string_view what, std::string_view text);

// `v` with `decimals` digits after the point, for people ("12.35").
std::string fixed(double v, int decimals);
// `v` as 16 hexadecimal digits, the way hashes are shown ("00c0ffee00c0ffee").
std::string hex64(std::uint64_t v);
// `text` cut to a readable length with control characters replaced, for quoting in a message.
std::string quote_arg(std::string_view text);
// " (did you mean 'x'?)" or "".
std::string did_you_mean(std::string_view given, std::span<const std::string_view> candidates);

// Writes "<command>: <message>" and a pointer to the help, and returns kExitUsage.
int usage_error(const CliContext& ctx, std::string_view command, const UsageError& e);

}  // namespace symb::apps
