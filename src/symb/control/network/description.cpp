#include "symb/control/network/description.hpp"

#include <charconv>
#include <cmath>
#include <string>

#include "symb/kernel/source_text.hpp"

namespace symb::control::network {

using kernel::Error;

namespace {

// Tokens longer than this are not numbers or keys anyone means; they are cut in messages.
constexpr std::size_t kShown = 24;

struct Token {
  std::string_view text;
  std::size_t line = 1, column = 1;
  bool first_on_line = false;
};

std::string where(const Token& t) { return kernel::location_prefix(t.line, t.column); }

// Splits into whitespace-separated tokens, dropping `#` comments.
std::vector<Token> tokenize(std::string_view text) {
  std::vector<Token> out;
  std::size_t line = 1, column = 1, i = 0;
  bool fresh_line = true;
  while (i < text.size()) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
      column = 1;
      ++i;
      fresh_line = true;
      continue;
    }
    if (c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v') {
      ++column;
      ++i;
      continue;
    }
    if (c == '#') {
      while (i < text.size() && text[i] != '\n') ++i;
      continue;
    }
    const std::size_t start = i;
    while (i < text.size() && text[i] != '\n' && text[i] != ' ' && text[i] != '\t' && text[i] != '\r' &&
           text[i] != '\f' && text[i] != '\v' && text[i] != '#')
      ++i;
    out.push_back({text.substr(start, i - start), line, column, fresh_line});
    column += i - start;
    fresh_line = false;
  }
  return out;
}

kernel::Result<float> number(const Token& t) {
  double v = 0;
  const char* end = t.text.data() + t.text.size();
  const char* begin = t.text.data();
  if (begin != end && *begin == '+') ++begin;  // from_chars refuses a leading '+'
  auto [ptr, ec] = std::from_chars(begin, end, v);
  if (ec == std::errc::result_out_of_range || (ec == std::errc() && ptr == end && std::fabs(v) > 3e38))
    return Error{where(t) + "'" + kernel::shortened(t.text, kShown) + "' is out of range"};
  if (ec != std::errc() || ptr != end)
    return Error{where(t) + "'" + kernel::shortened(t.text, kShown) + "' is not a number"};
  if (!std::isfinite(v)) return Error{where(t) + "'" + kernel::shortened(t.text, kShown) + "' is not a finite number"};
  return static_cast<float>(v);
}

bool looks_numeric(std::string_view s) {
  const char c = s.empty() ? ' ' : s[0];
  return (c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.';
}

kernel::Result<std::size_t> count(const Token& t, std::size_t max) {
  std::size_t v = 0;
  auto [ptr, ec] = std::from_chars(t.text.data(), t.text.data() + t.text.size(), v);
  if (ec != std::errc() || ptr != t.text.data() + t.text.size())
    return Error{where(t) + "'" + kernel::shortened(t.text, kShown) + "' is not a whole number"};
  if (v < 1 || v > max)
    return Error{where(t) + "must be 1.." + std::to_string(max) + ", got " + kernel::shortened(t.text, kShown)};
  return v;
}

}  // namespace

kernel::Result<std::vector<float>> parse_numbers(std::string_view text, std::size_t max_count) {
  std::vector<float> out;
  for (const Token& t : tokenize(text)) {
    if (out.size() >= max_count) return Error{where(t) + "more than " + std::to_string(max_count) + " numbers"};
    auto v = number(t);
    if (!v) return Error{v.error()};
    out.push_back(*v);
  }
  return out;
}

kernel::Result<Description> parse_description(std::string_view text) {
  const std::vector<Token> tokens = tokenize(text);
  Description d;
  // Where each key was given, for duplicate and count errors.
  std::optional<Token> type_at, inputs_at, layers_at, activation_at, scale_at, out_scale_at, tau_at, weights_at;
  std::vector<Token> layer_tokens;
  std::size_t i = 0;
  while (i < tokens.size()) {
    const Token& key = tokens[i];
    if (!key.first_on_line)
      return Error{where(key) + "one key a line: '" + kernel::shortened(key.text, kShown) +
                   "' follows the previous key's value"};
    // The values: the rest of the line, and for lists the lines after it that start with a number.
    std::vector<Token> values;
    std::size_t j = i + 1;
    for (; j < tokens.size(); ++j) {
      if (tokens[j].first_on_line && !looks_numeric(tokens[j].text)) break;
      values.push_back(tokens[j]);
    }
    auto seen = [&](std::optional<Token>& at) -> kernel::Status {
      if (at)
        return Error{where(key) + "'" + std::string(key.text) + "' given twice (first at line " +
                     std::to_string(at->line) + ")"};
      at = key;
      return {};
    };
    auto one = [&]() -> kernel::Status {
      if (values.empty()) return Error{where(key) + "'" + std::string(key.text) + "' needs a value"};
      if (values.size() > 1) return Error{where(values[1]) + "'" + std::string(key.text) + "' takes one value"};
      return {};
    };
    auto list = [&](std::vector<float>& into) -> kernel::Status {
      for (const Token& v : values) {
        if (into.size() >= kMaxGenome) return Error{where(v) + "more than " + std::to_string(kMaxGenome) + " numbers"};
        auto f = number(v);
        if (!f) return Error{f.error()};
        into.push_back(*f);
      }
      return {};
    };
    kernel::Status st;
    if (key.text == "type") {
      if (st = seen(type_at); st) st = one();
      if (st) {
        auto k = parse_kind(values[0].text);
        if (!k) return Error{where(values[0]) + k.error()};
        d.topology.kind = *k;
      }
    } else if (key.text == "inputs") {
      if (st = seen(inputs_at); st) st = one();
      if (st) {
        auto n = count(values[0], kMaxInputs);
        if (!n) return Error{n.error()};
        d.topology.inputs = *n;
      }
    } else if (key.text == "layers") {
      if (st = seen(layers_at); st) {
        if (values.empty()) st = Error{where(key) + "'layers' needs the layer sizes"};
        if (values.size() > kMaxLayers)
          st = Error{where(values[kMaxLayers]) + "at most " + std::to_string(kMaxLayers) + " layers"};
      }
      if (st) {
        d.topology.layers.clear();
        for (const Token& v : values) {
          auto n = count(v, kMaxLayerSize);
          if (!n) return Error{n.error()};
          d.topology.layers.push_back(*n);
        }
        layer_tokens = values;
      }
    } else if (key.text == "activation") {
      if (st = seen(activation_at); st) st = one();
      if (st) {
        auto a = parse_activation(values[0].text);
        if (!a) return Error{where(values[0]) + a.error()};
        d.topology.activation = *a;
      }
    } else if (key.text == "input_scale") {
      if (st = seen(scale_at); st)
        st = values.empty() ? Error{where(key) + "'input_scale' needs a value"} : list(d.input_scale);
    } else if (key.text == "output_scale") {
      if (st = seen(out_scale_at); st) st = one();
      if (st) {
        auto f = number(values[0]);
        if (!f) return Error{f.error()};
        if (*f <= 0) return Error{where(values[0]) + "output_scale must be positive"};
        d.output_scale = *f;
      }
    } else if (key.text == "tau") {
      if (st = seen(tau_at); st) st = values.empty() ? Error{where(key) + "'tau' needs a value"} : list(d.tau);
      if (st)
        for (std::size_t k = 0; k < d.tau.size(); ++k)
          if (d.tau[k] <= 0) return Error{where(values[k]) + "time constants must be positive"};
    } else if (key.text == "weights") {
      if (st = seen(weights_at); st) {
        d.weights.emplace();
        st = list(*d.weights);
      }
    } else {
      return Error{where(key) + "unknown key '" + kernel::shortened(key.text, kShown) +
                   "' (type, inputs, layers, activation, input_scale, output_scale, tau, weights)"};
    }
    if (!st) return Error{st.error()};
    i = j;
  }
  const Token end{{}, tokens.empty() ? 1 : tokens.back().line, 1, true};
  if (!type_at) return Error{where(end) + "missing 'type' (mlp, elman or ctrnn)"};
  if (!layers_at) return Error{where(end) + "missing 'layers'"};
  if (auto st = check(d.topology); !st)
    return Error{where(layer_tokens.empty() ? *layers_at : layer_tokens[0]) + st.error()};
  if (!d.input_scale.empty() && d.input_scale.size() != 1 && d.input_scale.size() != d.topology.inputs)
    return Error{where(*scale_at) + "input_scale takes one factor or one per input (" +
                 std::to_string(d.topology.inputs) + "), got " + std::to_string(d.input_scale.size())};
  if (!d.tau.empty()) {
    if (d.topology.kind != Kind::kCtrnn) return Error{where(*tau_at) + "'tau' is for ctrnn networks only"};
    if (d.tau.size() != 1 && d.tau.size() != d.topology.layers[0])
      return Error{where(*tau_at) + "tau takes one time constant or one per neuron (" +
                   std::to_string(d.topology.layers[0]) + "), got " + std::to_string(d.tau.size())};
  }
  if (activation_at && d.topology.kind == Kind::kCtrnn)
    return Error{where(*activation_at) + "a ctrnn always uses the logistic sigma: leave 'activation' out"};
  if (d.weights && d.weights->size() != genome_size(d.topology))
    return Error{where(*weights_at) + "this network has " + std::to_string(genome_size(d.topology)) + " weights, got " +
                 std::to_string(d.weights->size())};
  return d;
}

}  // namespace symb::control::network
