// CommandLine: how the shell reads one line of text. The tokenizer splits it into words,
// "double quoted" strings (with \" \\ \n \t escapes) and 'single quoted' strings (taken as they
// are), drops a # comment, and remembers each token's 1-based column (in bytes) so that every
// later error can point at the argument that was wrong. A line is refused whole, with the column,
// when it is longer than kMaxLineBytes, holds a control character or is not valid UTF-8: what a
// person can type is accepted, line noise and binary garbage are not.
//
// The option helpers read `--name value`, `--name=value` and `--flag` out of a command's
// arguments; their errors name the option and its column.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"

namespace symb::shell {

inline constexpr std::size_t kMaxLineBytes = 4096;

struct Token {
  std::string text;        // the word with its quotes and escapes resolved
  std::size_t column = 1;  // 1-based byte column of its first character in the line
  bool quoted = false;     // some part of it was quoted: never read as an option
};

// Splits `line` (without its line ending). An empty or comment-only line gives no tokens.
kernel::Result<std::vector<Token>> tokenize(std::string_view line);

// "column N: " + message: how every located error in the shell starts.
std::string at_column(std::size_t column, std::string_view message);
// `text` cut to a readable length with non-printable bytes shown as '?', for quoting input back.
std::string shorten(std::string_view text, std::size_t max = 40);
// `text` as a token the tokenizer reads back unchanged: as it is when it is a plain word, else
// double-quoted with escapes. Used wherever output must survive a split at white space.
std::string quote_word(std::string_view text);
// The first byte at which `text` is not valid UTF-8 (overlong forms, surrogates and code points
// above U+10FFFF included), or nothing when it is valid.
std::optional<std::size_t> invalid_utf8_at(std::string_view text);

// --- options -------------------------------------------------------------------------------------

struct OptionSpec {
  std::string_view name;        // "--priority"
  std::string_view value_name;  // "N"; empty for a flag
};

// A command's arguments with its options taken out.
class Args {
 public:
  // Splits `args` into positional arguments and options of `specs`. An unquoted token starting
  // with "--" must be one of the options (with a "did you mean" hint otherwise); "--" alone ends
  // the options. An option given twice or without its value is an error.
  static kernel::Result<Args> parse(std::span<const Token> args, std::span<const OptionSpec> specs);

  const std::vector<Token>& positional() const { return positional_; }
  bool has(std::string_view option) const { return find(option) != nullptr; }
  // The option's value token, or null when it was not given (or is a flag).
  const Token* value(std::string_view option) const;

  // Typed option values; nothing when the option was not given, an error naming it when its
  // value does not convert or is out of range.
  kernel::Result<std::optional<std::int64_t>> integer(std::string_view option, std::int64_t min,
                                                      std::int64_t max) const;
  kernel::Result<std::optional<kernel::Duration>> duration(std::string_view option, kernel::Duration min,
                                                           kernel::Duration max) const;
  // One of `choices`.
  kernel::Result<std::optional<std::string>> choice(std::string_view option,
                                                    std::span<const std::string_view> choices) const;

 private:
  struct Given {
    std::string_view name;  // the spec's name
    std::optional<Token> value;
    std::size_t column = 1;
  };
  const Given* find(std::string_view option) const;

  std::vector<Token> positional_;
  std::vector<Given> options_;
};

// Value parsers shared by positional arguments and options. `what` names the argument in the
// error ("priority", "option '--period'"); the error starts with the token's column.
kernel::Result<std::int64_t> parse_integer(const Token& t, std::string_view what, std::int64_t min, std::int64_t max);
kernel::Result<double> parse_real(const Token& t, std::string_view what);
// A duration with a unit (os::parse_duration: ns, us, ms, s, min, h), e.g. 30ms; "0" alone is
// also accepted.
kernel::Result<kernel::Duration> parse_duration(const Token& t, std::string_view what, kernel::Duration min,
                                                kernel::Duration max);

}  // namespace symb::shell
