// What the shell tests share: two registered task types (an emitter that sends its `value` every
// tick, a sink that takes what comes), a device with ioctls, a strict little JSON parser to check
// that --json output is valid and to read it back, and a whitespace splitter for tables.
#pragma once

#include <atomic>
#include <cctype>
#include <cstdlib>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "symb/io/device.hpp"
#include "symb/os/task.hpp"
#include "symb/os/task_type_registry.hpp"

namespace symb::shell::testing {

struct EmitterParams {
  double value = 1.0;
  std::string label = "none";
  bool loud = false;
};

class Emitter : public os::Task {
 public:
  explicit Emitter(const EmitterParams& p) : params_(p) { bind_parameters(params_); }

 protected:
  void on_tick() override { send(0, {static_cast<float>(params_.value)}); }

 private:
  EmitterParams params_;
};

class Sink : public os::Task {};

struct SinkParams {
  std::int64_t gain = 1;
};

// A type whose constructor throws (kind=0: a std::exception, kind=1: an int) or allocates `size`
// numbers: creating one must be an error reply, never the end of the process.
struct FragileParams {
  std::int64_t kind = -1;
  std::int64_t size = 0;
};
class Fragile : public os::Task {
 public:
  explicit Fragile(const FragileParams& p) : data_(static_cast<std::size_t>(p.size)) {
    if (p.kind == 0) throw std::runtime_error("fragile by request");
    if (p.kind == 1) throw 1;
  }

 private:
  std::vector<double> data_;
};

inline void add_fragile_type(os::TaskTypeRegistry& r) {
  os::ParamTable<FragileParams> f;
  f.add("kind", &FragileParams::kind).range(-1, 1).doc("what the constructor throws (-1: nothing)");
  f.add("size", &FragileParams::size).range(0, 9e18).doc("numbers it allocates");
  (void)r.add(os::declare_task_type("fragile", "throws on request", std::move(f),
                                    [](const FragileParams& p) { return std::make_unique<Fragile>(p); }));
}

inline void add_test_types(os::TaskTypeRegistry& r) {
  os::ParamTable<EmitterParams> e;
  e.add("value", &EmitterParams::value).range(-1e6, 1e6).doc("the number sent").live();
  e.add("label", &EmitterParams::label).doc("a free label").at_most(32).live();
  e.add("loud", &EmitterParams::loud).doc("unused flag").live();
  os::TaskType emitter = os::declare_task_type("emitter", "sends its value every tick", std::move(e),
                                               [](const EmitterParams& p) { return std::make_unique<Emitter>(p); });
  emitter.defaults.period = std::chrono::milliseconds(10);
  (void)r.add(std::move(emitter));
  os::ParamTable<SinkParams> k;
  k.add("gain", &SinkParams::gain).range(0, 100).doc("unused").live();
  os::TaskType sink = os::declare_task_type("sink", "takes whatever it is sent", std::move(k),
                                            [](const SinkParams&) { return std::make_unique<Sink>(); });
  sink.defaults.queue_capacity = 64;
  (void)r.add(std::move(sink));
}

// A device with a few typed ioctls.
class TestDevice final : public io::Device {
 public:
  explicit TestDevice(std::string name) : Device(std::move(name)) {
    os::ParamSpec baud{"baud", os::ParamType::kInt, std::int64_t{9600}, 300.0, 1e6, "bits per second"};
    add_ioctl({"baud", baud, "set the baud rate"}, [this](const os::ParamValue* v) -> kernel::Result<std::string> {
      baud_ = std::get<std::int64_t>(*v);
      return "baud " + std::to_string(baud_);
    });
    add_ioctl({"info", std::nullopt, "show the settings"},
              [this](const os::ParamValue*) -> kernel::Result<std::string> { return "baud=" + std::to_string(baud_); });
    add_ioctl({"flush", std::nullopt, "drop buffers"},
              [](const os::ParamValue*) -> kernel::Result<std::string> { return std::string(); });
  }
  kernel::Status open() override {
    open_ = true;
    return {};
  }
  void close() override { open_ = false; }
  bool is_open() const override { return open_; }
  std::int64_t baud() const { return baud_; }

 private:
  std::atomic<bool> open_{true};
  std::atomic<std::int64_t> baud_{9600};
};

// --- JSON ------------------------------------------------------------------------------------------

struct Json {
  using Array = std::vector<Json>;
  using Object = std::map<std::string, Json>;
  std::variant<std::nullptr_t, bool, double, std::string, Array, Object> v;

  bool is_array() const { return v.index() == 4; }
  bool is_object() const { return v.index() == 5; }
  const Array& array() const { return std::get<Array>(v); }
  const Object& object() const { return std::get<Object>(v); }
  const Json& operator[](const std::string& k) const { return object().at(k); }
  const Json& operator[](std::size_t i) const { return array().at(i); }
  double number() const { return std::get<double>(v); }
  const std::string& string() const { return std::get<std::string>(v); }
  bool boolean() const { return std::get<bool>(v); }
  bool is_null() const { return v.index() == 0; }
};

// Strict RFC 8259 parsing (no trailing commas, no comments, strings checked for raw control
// characters); nothing when the text is not exactly one JSON value (white space around it aside).
class JsonParser {
 public:
  static std::optional<Json> parse(std::string_view text) {
    JsonParser p(text);
    Json j;
    p.ws();
    if (!p.value(j, 0)) return std::nullopt;
    p.ws();
    if (p.i_ != text.size()) return std::nullopt;
    return j;
  }

 private:
  explicit JsonParser(std::string_view t) : t_(t) {}
  void ws() {
    while (i_ < t_.size() && (t_[i_] == ' ' || t_[i_] == '\n' || t_[i_] == '\r' || t_[i_] == '\t')) ++i_;
  }
  bool lit(std::string_view w) {
    if (t_.substr(i_, w.size()) != w) return false;
    i_ += w.size();
    return true;
  }
  bool value(Json& out, int depth) {
    if (depth > 64 || i_ >= t_.size()) return false;
    const char c = t_[i_];
    if (c == '{') return object(out, depth);
    if (c == '[') return array(out, depth);
    if (c == '"') {
      std::string s;
      if (!string(s)) return false;
      out.v = std::move(s);
      return true;
    }
    if (lit("true")) return out.v = true, true;
    if (lit("false")) return out.v = false, true;
    if (lit("null")) return out.v = nullptr, true;
    return number(out);
  }
  bool number(Json& out) {
    const std::size_t start = i_;
    if (i_ < t_.size() && t_[i_] == '-') ++i_;
    if (i_ >= t_.size() || !std::isdigit(static_cast<unsigned char>(t_[i_]))) return false;
    if (t_[i_] == '0' && i_ + 1 < t_.size() && std::isdigit(static_cast<unsigned char>(t_[i_ + 1]))) return false;
    while (i_ < t_.size() && std::isdigit(static_cast<unsigned char>(t_[i_]))) ++i_;
    if (i_ < t_.size() && t_[i_] == '.') {
      ++i_;
      if (i_ >= t_.size() || !std::isdigit(static_cast<unsigned char>(t_[i_]))) return false;
      while (i_ < t_.size() && std::isdigit(static_cast<unsigned char>(t_[i_]))) ++i_;
    }
    if (i_ < t_.size() && (t_[i_] == 'e' || t_[i_] == 'E')) {
      ++i_;
      if (i_ < t_.size() && (t_[i_] == '+' || t_[i_] == '-')) ++i_;
      if (i_ >= t_.size() || !std::isdigit(static_cast<unsigned char>(t_[i_]))) return false;
      while (i_ < t_.size() && std::isdigit(static_cast<unsigned char>(t_[i_]))) ++i_;
    }
    out.v = std::strtod(std::string(t_.substr(start, i_ - start)).c_str(), nullptr);
    return true;
  }
  bool string(std::string& s) {
    ++i_;  // '"'
    while (i_ < t_.size()) {
      const auto c = static_cast<unsigned char>(t_[i_++]);
      if (c == '"') return true;
      if (c < 0x20) return false;
      if (c != '\\') {
        s.push_back(static_cast<char>(c));
        continue;
      }
      if (i_ >= t_.size()) return false;
      const char e = t_[i_++];
      switch (e) {
        case '"': s += '"'; break;
        case '\\': s += '\\'; break;
        case '/': s += '/'; break;
        case 'b': s += '\b'; break;
        case 'f': s += '\f'; break;
        case 'n': s += '\n'; break;
        case 'r': s += '\r'; break;
        case 't': s += '\t'; break;
        case 'u': {
          if (i_ + 4 > t_.size()) return false;
          for (int k = 0; k < 4; ++k)
            if (!std::isxdigit(static_cast<unsigned char>(t_[i_ + static_cast<std::size_t>(k)]))) return false;
          const unsigned long cp = std::strtoul(std::string(t_.substr(i_, 4)).c_str(), nullptr, 16);
          i_ += 4;
          s += cp < 0x80 ? static_cast<char>(cp) : '?';
          break;
        }
        default: return false;
      }
    }
    return false;
  }
  bool array(Json& out, int depth) {
    ++i_;
    Json::Array a;
    ws();
    if (i_ < t_.size() && t_[i_] == ']') {
      ++i_;
      out.v = std::move(a);
      return true;
    }
    for (;;) {
      Json e;
      ws();
      if (!value(e, depth + 1)) return false;
      a.push_back(std::move(e));
      ws();
      if (i_ >= t_.size()) return false;
      if (t_[i_] == ',') {
        ++i_;
        continue;
      }
      if (t_[i_] != ']') return false;
      ++i_;
      out.v = std::move(a);
      return true;
    }
  }
  bool object(Json& out, int depth) {
    ++i_;
    Json::Object o;
    ws();
    if (i_ < t_.size() && t_[i_] == '}') {
      ++i_;
      out.v = std::move(o);
      return true;
    }
    for (;;) {
      ws();
      if (i_ >= t_.size() || t_[i_] != '"') return false;
      std::string k;
      if (!string(k)) return false;
      ws();
      if (i_ >= t_.size() || t_[i_] != ':') return false;
      ++i_;
      ws();
      Json e;
      if (!value(e, depth + 1)) return false;
      if (o.contains(k)) return false;  // duplicate keys: not what the shell should write
      o.emplace(std::move(k), std::move(e));
      ws();
      if (i_ >= t_.size()) return false;
      if (t_[i_] == ',') {
        ++i_;
        continue;
      }
      if (t_[i_] != '}') return false;
      ++i_;
      out.v = std::move(o);
      return true;
    }
  }

  std::string_view t_;
  std::size_t i_ = 0;
};

// A table's rows split at white space (the header row first).
inline std::vector<std::vector<std::string>> split_table(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::vector<std::string> row;
    std::string w;
    while (words >> w) row.push_back(w);
    if (!row.empty()) rows.push_back(std::move(row));
  }
  return rows;
}

}  // namespace symb::shell::testing
