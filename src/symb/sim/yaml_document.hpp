// The YAML scaffold of the sim layer's file parsers (scenarios, module kind files): yaml-cpp reads
// the YAML; a parser then walks the tree knowing its schema, so each value is read exactly once and
// an error names the file, line and column of the value that caused it ("file:LINE:COLUMN: what",
// kernel/source_text.hpp's form with the file in front). Before any tree is built the text is
// bounded: its size, the nesting of its flow collections (over the bytes) and of all collections
// (over the events), and one document per file. Inside the walk a failure is thrown as `Failure`
// (the walk is deep and every step can fail); parse_document catches it and everything yaml-cpp
// throws, so no exception leaves a parser built on it.
//
//   return yaml::parse_document<Kind>(text, file, "a module kind", kMaxBytes, kMaxNesting,
//       [](const yaml::Source& src, const YAML::Node& root) {
//         yaml::Map m(src, root, "the module kind", {"name", "body"});   // unknown keys refused
//         yaml::Reader rd(src);
//         Kind k;
//         k.mass = rd.number(m.require("mass"), "mass (kg)", 0.001, 100);  // finite, in range
//         return k;
//       });
#pragma once

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include "symb/kernel/result.hpp"
#include "symb/os/param.hpp"
#include "symb/sim/world_spec.hpp"

namespace symb::sim::yaml {

struct Failure {
  std::string message;
};

// The text of a value for an error message: short and printable.
std::string shown(std::string_view s);

// A byte count as a person writes a limit: "1 MiB", "64 KiB", "100 bytes".
std::string bytes_text(std::size_t bytes);

// Locations and failures for one file.
class Source {
 public:
  Source(std::string_view file, std::string_view text) : file_(file) {
    // Marks past the end (yaml-cpp reports "end of stream" after the last newline) are pulled
    // back onto the last line, so every error names a line the file has.
    lines_ = 1;
    std::size_t last_start = 0;
    for (std::size_t i = 0; i < text.size(); ++i)
      if (text[i] == '\n' && i + 1 < text.size()) {
        ++lines_;
        last_start = i + 1;
      }
    std::size_t end = text.size();
    while (end > last_start && (text[end - 1] == '\n' || text[end - 1] == '\r')) --end;
    last_line_length_ = static_cast<int>(end - last_start);
  }

  const std::string& file() const { return file_; }

  SourceLocation at(const YAML::Mark& m, int column_offset = 0) const {
    SourceLocation loc{file_, 1, 1};
    if (m.is_null() || m.line < 0) return loc;
    if (m.line + 1 > lines_) {
      loc.line = lines_;
      loc.column = last_line_length_ + 1;
      return loc;
    }
    loc.line = m.line + 1;
    loc.column = std::max(0, m.column) + 1 + column_offset;
    return loc;
  }
  SourceLocation at(const YAML::Node& n) const { return at(n.Mark()); }

  [[noreturn]] void fail(const SourceLocation& where, const std::string& what) const {
    throw Failure{where.str() + ": " + what};
  }
  [[noreturn]] void fail(const YAML::Node& n, const std::string& what) const { fail(at(n), what); }

 private:
  std::string file_;
  int lines_ = 1;
  int last_line_length_ = 0;
};

// Zeroth pass, over the bytes: flow collections ('[' and '{') nested deeper than `max_nesting`.
// yaml-cpp's scanner reads a flow collection ahead before it hands over its first event (any '['
// may start a simple key), about 2.5 us a byte: a MiB of '[' cost 2.5 s before the event pass
// could stop it; this finds the first bracket past the bound in a millisecond. It counts only the
// brackets that open a collection (any in flow context; in block context one that starts a value
// or a line), skips quoted scalars, comments and block scalars ('|', '>'), and stops counting at
// anything it cannot place (an unterminated quote), so it never rejects a file that nests less;
// the event pass below stays the authority. Returns the 1-based line and column of the bracket.
std::optional<std::pair<int, int>> flow_too_deep(std::string_view t, int max_nesting);

// First pass over the events: nesting depth and document count, before any tree is built.
// yaml-cpp recurses once per level (it stops itself at 2000); this stops at `max_nesting`.
class ShapeCheck : public YAML::EventHandler {
 public:
  ShapeCheck(const Source& src, std::string_view what, int max_nesting)
      : src_(src), what_(what), max_nesting_(max_nesting) {}
  void OnDocumentStart(const YAML::Mark& m) override {
    if (++documents_ > 1) src_.fail(src_.at(m), what_ + " file holds one YAML document; this is a second one");
  }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t, const std::string&) override {}
  void OnSequenceStart(const YAML::Mark& m, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    enter(m);
  }
  void OnSequenceEnd() override { --depth_; }
  void OnMapStart(const YAML::Mark& m, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    enter(m);
  }
  void OnMapEnd() override { --depth_; }

 private:
  void enter(const YAML::Mark& m) {
    if (++depth_ > max_nesting_)
      src_.fail(src_.at(m), "nested more than " + std::to_string(max_nesting_) + " levels deep");
  }
  const Source& src_;
  std::string what_;
  int max_nesting_;
  int documents_ = 0;
  int depth_ = 0;
};

// A mapping whose keys are checked against a schema: known, plain, each once.
class Map {
 public:
  Map(const Source& src, const YAML::Node& node, std::string_view what, std::initializer_list<std::string_view> keys)
      : src_(src), node_(node), what_(what) {
    if (!node.IsMap()) src.fail(node, std::string(what) + " must be a mapping (key: value, ...)" + got(node));
    const std::vector<std::string_view> known(keys);
    for (const auto& kv : node) {
      const YAML::Node& k = kv.first;
      if (!k.IsScalar()) src.fail(k, "a key in " + std::string(what) + " must be a plain name");
      const std::string& name = k.Scalar();
      if (std::find(known.begin(), known.end(), name) == known.end()) {
        std::string msg = "unknown key '" + shown(name) + "' in " + std::string(what);
        if (auto hint = os::closest_name(name, known); !hint.empty()) {
          msg += " (did you mean '" + hint + "'?)";
        } else {
          msg += " (known keys:";
          for (auto kn : known) msg += " " + std::string(kn);
          msg += ")";
        }
        src.fail(k, msg);
      }
      for (const auto& e : entries_)
        if (e.name == name)
          src.fail(k, "key '" + name + "' given twice in " + std::string(what) + " (first at line " +
                          std::to_string(src.at(e.key).line) + ")");
      entries_.push_back({name, k, kv.second});
    }
  }

  // The value of `key`; an undefined node when absent.
  YAML::Node get(std::string_view key) const {
    for (const auto& e : entries_)
      if (e.name == key) return e.value;
    return YAML::Node(YAML::NodeType::Undefined);
  }
  bool has(std::string_view key) const { return get(key).IsDefined(); }
  YAML::Node require(std::string_view key) const {
    YAML::Node v = get(key);
    if (!v.IsDefined()) src_.fail(node_, std::string(what_) + " needs '" + std::string(key) + "'");
    return v;
  }
  const YAML::Node& node() const { return node_; }

  static std::string got(const YAML::Node& n) {
    switch (n.Type()) {
      case YAML::NodeType::Null: return ", got nothing";
      case YAML::NodeType::Scalar: return ", got '" + shown(n.Scalar()) + "'";
      case YAML::NodeType::Sequence: return ", got a sequence";
      case YAML::NodeType::Map: return ", got a mapping";
      default: return "";
    }
  }

 private:
  struct Entry {
    std::string name;
    YAML::Node key;
    YAML::Node value;
  };
  const Source& src_;
  YAML::Node node_;
  std::string what_;
  std::vector<Entry> entries_;
};

// Scalars read as the schema wants them, each checked (finite, in range) or failed at its place.
class Reader {
 public:
  explicit Reader(const Source& src) : src_(src) {}

  std::string text(const YAML::Node& n, std::string_view what) const {
    if (!n.IsScalar()) src_.fail(n, std::string(what) + " must be a single value" + Map::got(n));
    return n.Scalar();
  }

  double number(const YAML::Node& n, std::string_view what, double lo, double hi) const {
    const std::string s = text(n, what);
    std::string_view v = s;
    if (!v.empty() && v.front() == '+') v.remove_prefix(1);
    double d = 0;
    auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), d);
    if (v.empty() || ec != std::errc() || end != v.data() + v.size() || !std::isfinite(d))
      src_.fail(n, std::string(what) + " must be a finite number, got '" + shown(s) + "'");
    if (d < lo || d > hi)
      src_.fail(n, std::string(what) + " must be in " + fmt(lo) + ".." + fmt(hi) + ", got " + shown(s));
    return d;
  }

  std::int64_t integer(const YAML::Node& n, std::string_view what, std::int64_t lo, std::int64_t hi) const {
    const std::string s = text(n, what);
    std::string_view v = s;
    if (!v.empty() && v.front() == '+') v.remove_prefix(1);
    std::int64_t i = 0;
    auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), i);
    if (v.empty() || ec != std::errc() || end != v.data() + v.size() || i < lo || i > hi)
      src_.fail(n, std::string(what) + " must be an integer in " + std::to_string(lo) + ".." + std::to_string(hi) +
                       ", got '" + shown(s) + "'");
    return i;
  }

  std::uint64_t unsigned_integer(const YAML::Node& n, std::string_view what) const {
    const std::string s = text(n, what);
    std::uint64_t u = 0;
    auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), u);
    if (s.empty() || ec != std::errc() || end != s.data() + s.size())
      src_.fail(n, std::string(what) + " must be an unsigned integer (0.." +
                       std::to_string(std::numeric_limits<std::uint64_t>::max()) + "), got '" + shown(s) + "'");
    return u;
  }

  bool boolean(const YAML::Node& n, std::string_view what) const {
    const std::string s = text(n, what);
    if (s == "true" || s == "True" || s == "TRUE") return true;
    if (s == "false" || s == "False" || s == "FALSE") return false;
    src_.fail(n, std::string(what) + " must be true or false, got '" + shown(s) + "'");
  }

  // A list that may also be written as nothing at all (`tasks:` with no entries).
  std::vector<YAML::Node> list(const YAML::Node& n, std::string_view what, std::size_t max) const {
    std::vector<YAML::Node> out;
    if (!n.IsDefined() || n.IsNull()) return out;
    if (!n.IsSequence()) src_.fail(n, std::string(what) + " must be a list (- item, or [a, b])" + Map::got(n));
    if (n.size() > max)
      src_.fail(n, std::string(what) + " has " + std::to_string(n.size()) + " entries; at most " + std::to_string(max) +
                       " are allowed");
    for (const auto& item : n) out.push_back(item);
    return out;
  }

  static std::string fmt(double v) {
    std::ostringstream o;
    o << v;
    return o.str();
  }

 protected:
  const Source& src_;
};

// The text of the file at `path`, refused when larger than `max_bytes`; `noun` names the kind of
// file in messages ("scenario"). Errors are "path: why" or "path:1:1: why".
kernel::Result<std::string> read_text_file(const std::string& path, std::size_t max_bytes, std::string_view noun);

// Text -> T through `walk(src, root)`, after the bounds above: at most `max_bytes` bytes, nesting
// at most `max_nesting` deep, one document. `what` names the kind of file in messages ("a
// scenario"). Every failure comes back as "file:LINE:COLUMN: what"; nothing is thrown.
template <class T, class Walk>
kernel::Result<T> parse_document(std::string_view text, std::string_view file, std::string_view what,
                                 std::size_t max_bytes, int max_nesting, Walk&& walk) {
  const Source src(file, text);
  const SourceLocation start{src.file(), 1, 1};
  const std::string noun(what.substr(what.find(' ') == std::string_view::npos ? 0 : what.find(' ') + 1));
  try {
    if (text.size() > max_bytes)
      return kernel::Error{start.str() + ": the file has " + std::to_string(text.size()) + " bytes; " +
                           std::string(what) + " may have at most " + bytes_text(max_bytes)};
    if (const auto deep = flow_too_deep(text, max_nesting))
      return kernel::Error{SourceLocation{src.file(), deep->first, deep->second}.str() + ": nested more than " +
                           std::to_string(max_nesting) + " levels deep"};
    const std::string copy(text);
    {
      std::istringstream in(copy);
      YAML::Parser events(in);
      ShapeCheck shape(src, what, max_nesting);
      while (events.HandleNextDocument(shape)) {
      }
    }
    return walk(src, YAML::Load(copy));
  } catch (const Failure& f) {
    return kernel::Error{f.message};
  } catch (const YAML::Exception& e) {
    return kernel::Error{src.at(e.mark).str() + ": invalid YAML: " + e.msg};
  } catch (const std::exception& e) {
    return kernel::Error{start.str() + ": cannot read the " + noun + ": " + e.what()};
  } catch (...) {
    return kernel::Error{start.str() + ": cannot read the " + noun};
  }
}

}  // namespace symb::sim::yaml
