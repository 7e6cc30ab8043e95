#include "symb/sim/yaml_document.hpp"

#include <filesystem>
#include <fstream>

namespace symb::sim::yaml {

std::string bytes_text(std::size_t bytes) {
  if (bytes > 0 && bytes % (std::size_t{1} << 20) == 0) return std::to_string(bytes >> 20) + " MiB";
  if (bytes > 0 && bytes % 1024 == 0) return std::to_string(bytes >> 10) + " KiB";
  return std::to_string(bytes) + " bytes";
}

std::string shown(std::string_view s) {
  std::string out;
  for (char ch : s.substr(0, 40)) {
    const auto c = static_cast<unsigned char>(ch);
    out += (c >= 0x20 && c < 0x7f) ? ch : '?';
  }
  if (s.size() > 40) out += "...";
  return out;
}

std::optional<std::pair<int, int>> flow_too_deep(std::string_view t, int max_nesting) {
  int depth = 0, line = 1;
  std::size_t line_start = 0;
  char prev = '\n';              // the last character that is not a blank on this line; '\n' at its start
  bool blank_before = true;      // a blank (or the line start) comes right before i
  int block_scalar_indent = -1;  // >= 0: inside a block scalar's lines, indented more than this
  for (std::size_t i = 0; i < t.size(); ++i) {
    const char c = t[i];
    if (c == '\n') {
      ++line;
      line_start = i + 1;
      prev = '\n';
      blank_before = true;
      if (block_scalar_indent >= 0) {  // skip the scalar's lines: blank ones or indented deeper
        std::size_t k = i + 1;
        for (;;) {
          std::size_t e = k;
          while (e < t.size() && t[e] == ' ') ++e;
          if (e < t.size() && t[e] != '\n' && t[e] != '\r' && static_cast<int>(e - k) <= block_scalar_indent) break;
          const std::size_t nl = t.find('\n', e);
          if (nl == std::string_view::npos) return std::nullopt;
          ++line;
          k = nl + 1;
        }
        line_start = k;
        i = k - 1;
        block_scalar_indent = -1;
      }
      continue;
    }
    if (c == ' ' || c == '\t' || c == '\r') {
      blank_before = true;
      continue;
    }
    const bool token_start = blank_before || prev == '[' || prev == '{' || prev == ',';
    if (c == '#' && blank_before) {
      const std::size_t nl = t.find('\n', i);
      if (nl == std::string_view::npos) return std::nullopt;
      i = nl - 1;
      continue;
    }
    if ((c == '\'' || c == '"') && token_start) {
      std::size_t k = i + 1;
      for (;; ++k) {
        if (k >= t.size()) return std::nullopt;
        if (t[k] == '\n') {
          ++line;
          line_start = k + 1;
        } else if (c == '"' && t[k] == '\\') {
          ++k;
        } else if (t[k] == c) {
          if (c == '\'' && k + 1 < t.size() && t[k + 1] == '\'') {
            ++k;
            continue;
          }
          break;
        }
      }
      i = k;
      prev = c;
      blank_before = false;
      continue;
    }
    if ((c == '|' || c == '>') && depth == 0 && blank_before && prev == ':') {
      std::size_t indent = 0;
      while (line_start + indent < t.size() && t[line_start + indent] == ' ') ++indent;
      block_scalar_indent = static_cast<int>(indent);
    } else if ((c == '[' || c == '{') &&
               (depth > 0 || (blank_before && (prev == '\n' || prev == ':' || prev == '-' || prev == '?')))) {
      if (++depth > max_nesting) return std::pair{line, static_cast<int>(i - line_start) + 1};
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
    prev = c;
    blank_before = false;
  }
  return std::nullopt;
}

kernel::Result<std::string> read_text_file(const std::string& path, std::size_t max_bytes, std::string_view noun) {
  const std::string where = SourceLocation{path}.str();
  const std::string what(noun);
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status))
    return kernel::Error{where + ": cannot open the " + what + " file" +
                         (ec ? " (" + ec.message() + ")" : std::string())};
  if (!std::filesystem::is_regular_file(status)) return kernel::Error{where + ": not a regular file"};
  std::ifstream in(path, std::ios::binary);
  if (!in) return kernel::Error{where + ": cannot open the " + what + " file"};
  std::string text(max_bytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  if (in.bad()) return kernel::Error{where + ": cannot read the " + what + " file"};
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > max_bytes) return kernel::Error{where + ":1:1: the file is larger than " + bytes_text(max_bytes)};
  return text;
}

}  // namespace symb::sim::yaml
