#include "symb/shell/command_line.hpp"

#include <cmath>
#include <cstdio>

#include "symb/os/param.hpp"

namespace symb::shell {

using kernel::Error;
using kernel::Result;

std::string at_column(std::size_t column, std::string_view message) {
  return "column " + std::to_string(column) + ": " + std::string(message);
}

std::string shorten(std::string_view text, std::size_t max) {
  std::string s;
  for (char ch : text.substr(0, max)) {
    const auto c = static_cast<unsigned char>(ch);
    s.push_back(c < 0x20 || c >= 0x7f ? '?' : ch);
  }
  if (text.size() > max) s += "...";
  return s;
}

std::optional<std::size_t> invalid_utf8_at(std::string_view text) {
  std::size_t i = 0;
  while (i < text.size()) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c < 0x80) {
      ++i;
      continue;
    }
    std::size_t n = 0;
    std::uint32_t cp = 0;
    if (c >= 0xc2 && c <= 0xdf) {
      n = 1;
      cp = c & 0x1fu;
    } else if (c >= 0xe0 && c <= 0xef) {
      n = 2;
      cp = c & 0x0fu;
    } else if (c >= 0xf0 && c <= 0xf4) {
      n = 3;
      cp = c & 0x07u;
    } else {
      return i;  // a continuation byte out of place, or a lead byte no valid sequence uses
    }
    if (i + n >= text.size()) return i;  // cut short by the end of the text
    for (std::size_t k = 1; k <= n; ++k) {
      const auto cc = static_cast<unsigned char>(text[i + k]);
      if ((cc & 0xc0u) != 0x80u) return i;
      cp = (cp << 6) | (cc & 0x3fu);
    }
    // Overlong forms, UTF-16 surrogates and code points past U+10FFFF are not UTF-8.
    if ((n == 2 && cp < 0x800) || (n == 3 && cp < 0x10000) || (cp >= 0xd800 && cp <= 0xdfff) || cp > 0x10ffff) return i;
    i += n + 1;
  }
  return std::nullopt;
}

Result<std::vector<Token>> tokenize(std::string_view line) {
  if (line.size() > kMaxLineBytes)
    return Error{at_column(kMaxLineBytes + 1, "line is longer than " + std::to_string(kMaxLineBytes) + " bytes")};
  // Whole-line checks first, so that a bad byte is reported where it is, whatever surrounds it.
  for (std::size_t i = 0; i < line.size(); ++i) {
    const auto c = static_cast<unsigned char>(line[i]);
    if ((c < 0x20 && c != '\t') || c == 0x7f) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "0x%02x", c);
      return Error{at_column(i + 1, std::string("control character ") + hex)};
    }
  }
  if (auto bad = invalid_utf8_at(line)) return Error{at_column(*bad + 1, "invalid UTF-8")};

  std::vector<Token> out;
  std::size_t i = 0;
  const auto blank = [&](std::size_t at) { return line[at] == ' ' || line[at] == '\t'; };
  while (true) {
    while (i < line.size() && blank(i)) ++i;
    if (i >= line.size() || line[i] == '#') break;
    Token t;
    t.column = i + 1;
    // A token runs to the next unquoted blank; quoted parts join the words around them, as in sh.
    while (i < line.size() && !blank(i)) {
      const char c = line[i];
      if (c == '\'') {
        const std::size_t open = i++;
        const std::size_t close = line.find('\'', i);
        if (close == std::string_view::npos) return Error{at_column(open + 1, "unterminated single quote")};
        t.text.append(line.substr(i, close - i));
        t.quoted = true;
        i = close + 1;
      } else if (c == '"') {
        const std::size_t open = i++;
        bool closed = false;
        while (i < line.size()) {
          const char q = line[i++];
          if (q == '"') {
            closed = true;
            break;
          }
          if (q != '\\') {
            t.text.push_back(q);
            continue;
          }
          if (i >= line.size()) break;
          const char e = line[i++];
          switch (e) {
            case '"': t.text.push_back('"'); break;
            case '\\': t.text.push_back('\\'); break;
            case 'n': t.text.push_back('\n'); break;
            case 't': t.text.push_back('\t'); break;
            default:
              return Error{at_column(
                  i - 1, "unknown escape '\\" + shorten(line.substr(i - 1, 1)) + "' (use \\\" \\\\ \\n or \\t)")};
          }
        }
        if (!closed) return Error{at_column(open + 1, "unterminated double quote")};
        t.quoted = true;
      } else {
        t.text.push_back(c);
        ++i;
      }
    }
    out.push_back(std::move(t));
  }
  return out;
}

std::string quote_word(std::string_view text) {
  bool plain = !text.empty() && text.front() != '#';
  for (char c : text)
    if (c == ' ' || c == '\t' || c == '"' || c == '\'' || c == '\\' || static_cast<unsigned char>(c) < 0x20 ||
        c == 0x7f)
      plain = false;
  if (plain) return std::string(text);
  std::string q = "\"";
  for (char c : text) {
    switch (c) {
      case '"': q += "\\\""; break;
      case '\\': q += "\\\\"; break;
      case '\n': q += "\\n"; break;
      case '\t': q += "\\t"; break;
      default: q.push_back(static_cast<unsigned char>(c) < 0x20 || c == 0x7f ? '?' : c);
    }
  }
  q += '"';
  return q;
}

// --- value parsers -------------------------------------------------------------------------------

namespace {

// The os layer's parameter parser does the conversions; its messages start with the parameter's
// name, which here is replaced by what the shell calls the argument.
Result<os::ParamValue> parse_as(const Token& t, std::string_view what, os::ParamType type, std::optional<double> min,
                                std::optional<double> max) {
  os::ParamSpec spec;
  spec.name = "x";
  spec.type = type;
  spec.min = min;
  spec.max = max;
  auto v = os::parse_param_value(spec, t.text);
  if (v) return v;
  std::string msg = v.error();
  const std::string_view prefix = "parameter 'x': ";
  if (msg.starts_with(prefix)) msg.erase(0, prefix.size());
  return Error{at_column(t.column, std::string(what) + ": " + msg)};
}

}  // namespace

Result<std::int64_t> parse_integer(const Token& t, std::string_view what, std::int64_t min, std::int64_t max) {
  auto v = parse_as(t, what, os::ParamType::kInt, std::nullopt, std::nullopt);
  if (!v) return Error{v.error()};
  const std::int64_t i = std::get<std::int64_t>(*v);
  // Checked here rather than by the schema, whose bounds are doubles printed as 1e+06.
  if (i < min || i > max)
    return Error{at_column(t.column, std::string(what) + ": value " + std::to_string(i) + " is outside [" +
                                         std::to_string(min) + ", " + std::to_string(max) + "]")};
  return i;
}

Result<double> parse_real(const Token& t, std::string_view what) {
  auto v = parse_as(t, what, os::ParamType::kReal, std::nullopt, std::nullopt);
  if (!v) return Error{v.error()};
  return std::get<double>(*v);
}

Result<kernel::Duration> parse_duration(const Token& t, std::string_view what, kernel::Duration min,
                                        kernel::Duration max) {
  kernel::Duration d{0};
  if (t.text != "0") {
    auto v = os::parse_duration(t.text);
    if (!v) return Error{at_column(t.column, std::string(what) + ": " + v.error())};
    d = *v;
  }
  if (d < min || d > max) {
    const auto text = [](kernel::Duration x) { return os::format_param_value(os::ParamValue{x}); };
    return Error{
        at_column(t.column, std::string(what) + ": " + text(d) + " is outside [" + text(min) + ", " + text(max) + "]")};
  }
  return d;
}

// --- options -------------------------------------------------------------------------------------

Result<Args> Args::parse(std::span<const Token> args, std::span<const OptionSpec> specs) {
  Args out;
  bool options_over = false;
  for (std::size_t k = 0; k < args.size(); ++k) {
    const Token& t = args[k];
    if (options_over || t.quoted || !t.text.starts_with("--")) {
      out.positional_.push_back(t);
      continue;
    }
    if (t.text == "--") {
      options_over = true;
      continue;
    }
    std::string_view name = t.text;
    std::optional<Token> inline_value;
    if (auto eq = name.find('='); eq != std::string_view::npos) {
      Token v;
      v.text = std::string(name.substr(eq + 1));
      v.column = t.column + eq + 1;
      inline_value = std::move(v);
      name = name.substr(0, eq);
    }
    const OptionSpec* spec = nullptr;
    for (const auto& s : specs)
      if (s.name == name) spec = &s;
    if (spec == nullptr) {
      std::vector<std::string_view> names;
      for (const auto& s : specs) names.push_back(s.name);
      std::string msg = "unknown option '" + shorten(name) + "'";
      if (auto hint = os::closest_name(name, names); !hint.empty()) msg += " (did you mean '" + hint + "'?)";
      if (specs.empty()) msg += " (this command takes no options)";
      return Error{at_column(t.column, msg)};
    }
    if (out.find(spec->name) != nullptr)
      return Error{at_column(t.column, "option '" + std::string(spec->name) + "' given twice")};
    Given g{spec->name, std::nullopt, t.column};
    if (spec->value_name.empty()) {
      if (inline_value) return Error{at_column(t.column, "option '" + std::string(spec->name) + "' takes no value")};
    } else if (inline_value) {
      g.value = std::move(inline_value);
    } else {
      if (k + 1 >= args.size())
        return Error{at_column(t.column, "option '" + std::string(spec->name) + "' needs a value (" +
                                             std::string(spec->value_name) + ")")};
      g.value = args[++k];
    }
    out.options_.push_back(std::move(g));
  }
  return out;
}

const Args::Given* Args::find(std::string_view option) const {
  for (const auto& g : options_)
    if (g.name == option) return &g;
  return nullptr;
}

const Token* Args::value(std::string_view option) const {
  const Given* g = find(option);
  return g != nullptr && g->value ? &*g->value : nullptr;
}

Result<std::optional<std::int64_t>> Args::integer(std::string_view option, std::int64_t min, std::int64_t max) const {
  const Token* t = value(option);
  if (t == nullptr) return std::optional<std::int64_t>{};
  auto v = parse_integer(*t, "option '" + std::string(option) + "'", min, max);
  if (!v) return Error{v.error()};
  return std::optional<std::int64_t>(*v);
}

Result<std::optional<kernel::Duration>> Args::duration(std::string_view option, kernel::Duration min,
                                                       kernel::Duration max) const {
  const Token* t = value(option);
  if (t == nullptr) return std::optional<kernel::Duration>{};
  auto v = parse_duration(*t, "option '" + std::string(option) + "'", min, max);
  if (!v) return Error{v.error()};
  return std::optional<kernel::Duration>(*v);
}

Result<std::optional<std::string>> Args::choice(std::string_view option,
                                                std::span<const std::string_view> choices) const {
  const Token* t = value(option);
  if (t == nullptr) return std::optional<std::string>{};
  for (std::string_view c : choices)
    if (t->text == c) return std::optional<std::string>(t->text);
  std::string list;
  for (std::string_view c : choices) list += (list.empty() ? "" : ", ") + std::string(c);
  std::string msg =
      "option '" + std::string(option) + "': expected one of " + list + ", got '" + shorten(t->text) + "'";
  if (auto hint = os::closest_name(t->text, choices); !hint.empty()) msg += " (did you mean '" + hint + "'?)";
  return Error{at_column(t->column, msg)};
}

}  // namespace symb::shell
