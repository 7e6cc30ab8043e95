#include "symb/evo/genome/genome.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <optional>
#include <system_error>
#include <utility>

#include "symb/control/ahhs/parser.hpp"
#include "symb/kernel/source_text.hpp"

namespace symb::evo {

using kernel::Error;

namespace {

// ---------------------------------------------------------------------------------------------
// Text form: tokens of one line at a time, so that for ahhs and linda nothing after the `genome`
// line is looked at by this parser (the embedded description is the controller parser's business).

using Token = kernel::TextToken;
using kernel::location_prefix;

// Shown in a message: a token cut short, so a huge token cannot make a huge error.
std::string shown(std::string_view s) { return s.size() <= 32 ? std::string(s) : std::string(s.substr(0, 29)) + "..."; }

bool looks_numeric(std::string_view s) {
  const char c = s.empty() ? ' ' : s[0];
  return (c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.';
}

kernel::Result<double> parse_number(const Token& t) {
  const char* first = t.text.data();
  const char* last = first + t.text.size();
  if (first != last && *first == '+') ++first;  // from_chars refuses a leading '+'
  double v = 0;
  auto [ptr, ec] = std::from_chars(first, last, v);
  if (ec == std::errc::result_out_of_range) return t.error("number '" + shown(t.text) + "' out of range");
  if (ec != std::errc{} || ptr != last || first == last) return t.error("'" + shown(t.text) + "' is not a number");
  if (!std::isfinite(v)) return t.error("number '" + shown(t.text) + "' is not finite");
  return v;
}

// "L:C: rest" with L moved down by `offset` lines; a message without a location gets the line
// where the embedded text starts.
std::string rebase(const std::string& message, std::size_t offset) {
  const kernel::LocatedMessage m = kernel::split_location(message);
  if (!m.at) return location_prefix(offset + 1, 1) + message;
  return location_prefix(m.at->line + offset, m.at->column) + std::string(m.message);
}

class RealParser {
 public:
  // Feeds one line's tokens (never empty).
  kernel::Status statement(const std::vector<Token>& s) {
    const Token& key = s[0];
    if (looks_numeric(key.text)) {
      if (!in_values_)
        return key.error("number '" + shown(key.text) + "' outside a list: a line starts with bounds, sigma or values");
      return numbers(s, 0);
    }
    in_values_ = false;
    if (key.text == "genome") return key.error("'genome' given twice (first at line " + std::to_string(header_) + ")");
    if (key.text == "bounds") return bounds(s);
    if (key.text == "sigma") return sigma(s);
    if (key.text == "values") {
      if (values_at_) return twice(key, *values_at_);
      values_at_ = key;
      in_values_ = true;
      return numbers(s, 1);
    }
    return key.error("unknown key '" + shown(key.text) + "' (bounds, sigma or values)");
  }

  kernel::Result<RealGenome> finish(std::size_t end_line, std::size_t end_column) {
    if (!values_at_) return Error{location_prefix(end_line, end_column) + "missing 'values' (the genes)"};
    if (!(g_.lo < g_.hi))
      return hi_at_->error("bounds: lo " + kernel::shortest_text<double>(g_.lo) + " must be below hi " +
                           kernel::shortest_text<double>(g_.hi));
    const Token& sigma_at = sigma_value_at_ ? *sigma_value_at_ : *values_at_;
    if (!(g_.sigma_min > 0))
      return (min_at_ ? *min_at_ : sigma_at)
          .error("sigma min " + kernel::shortest_text<double>(g_.sigma_min) + " must be above 0");
    if (!(g_.sigma_min <= g_.sigma_max))
      return (max_at_ ? *max_at_ : sigma_at)
          .error("sigma max " + kernel::shortest_text<double>(g_.sigma_max) + " below min " +
                 kernel::shortest_text<double>(g_.sigma_min));
    if (!(g_.sigma >= g_.sigma_min && g_.sigma <= g_.sigma_max))
      return sigma_at.error("sigma " + kernel::shortest_text<double>(g_.sigma) + " outside [" +
                            kernel::shortest_text<double>(g_.sigma_min) + ", " +
                            kernel::shortest_text<double>(g_.sigma_max) + "] (its min and max)");
    for (std::size_t i = 0; i < g_.values.size(); ++i)
      if (g_.values[i] < g_.lo || g_.values[i] > g_.hi)
        return value_at_[i].error("value " + std::to_string(i) + ": " + kernel::shortest_text<double>(g_.values[i]) +
                                  " outside bounds [" + kernel::shortest_text<double>(g_.lo) + ", " +
                                  kernel::shortest_text<double>(g_.hi) + "]");
    if (auto st = check(g_); !st) return Error{location_prefix(header_, 1) + st.error()};  // unreachable: checked above
    return std::move(g_);
  }

  std::size_t header_ = 1;

 private:
  static Error twice(const Token& key, const Token& first) {
    return key.error("'" + std::string(key.text) + "' given twice (first at line " + std::to_string(first.line) + ")");
  }

  kernel::Status numbers(const std::vector<Token>& s, std::size_t from) {
    for (std::size_t i = from; i < s.size(); ++i) {
      if (g_.values.size() >= kMaxRealGenes)
        return s[i].error("more than " + std::to_string(kMaxRealGenes) + " values");
      auto v = parse_number(s[i]);
      if (!v) return Error{v.error()};
      g_.values.push_back(*v);
      value_at_.push_back(s[i]);
    }
    return {};
  }

  kernel::Status bounds(const std::vector<Token>& s) {
    if (bounds_at_) return twice(s[0], *bounds_at_);
    bounds_at_ = s[0];
    if (s.size() < 3) return s.back().error_after("bounds needs two numbers: lo hi");
    if (s.size() > 3) return s[3].error("bounds takes two numbers: lo hi");
    auto lo = parse_number(s[1]);
    if (!lo) return Error{lo.error()};
    auto hi = parse_number(s[2]);
    if (!hi) return Error{hi.error()};
    g_.lo = *lo;
    g_.hi = *hi;
    hi_at_ = s[2];
    return {};
  }

  kernel::Status sigma(const std::vector<Token>& s) {
    if (sigma_at_) return twice(s[0], *sigma_at_);
    sigma_at_ = s[0];
    if (s.size() < 2) return s[0].error_after("sigma needs a value");
    auto v = parse_number(s[1]);
    if (!v) return Error{v.error()};
    g_.sigma = *v;
    sigma_value_at_ = s[1];
    for (std::size_t i = 2; i < s.size(); i += 2) {
      const bool is_min = s[i].text == "min";
      if (!is_min && s[i].text != "max")
        return s[i].error("sigma takes 'min A' and 'max B' after its value, not '" + shown(s[i].text) + "'");
      std::optional<Token>& seen = is_min ? min_at_ : max_at_;
      if (seen) return s[i].error("'" + std::string(s[i].text) + "' given twice");
      if (i + 1 >= s.size()) return s[i].error_after("'" + std::string(s[i].text) + "' needs a number");
      auto n = parse_number(s[i + 1]);
      if (!n) return Error{n.error()};
      seen = s[i + 1];
      (is_min ? g_.sigma_min : g_.sigma_max) = *n;
    }
    return {};
  }

  RealGenome g_;
  std::vector<Token> value_at_;
  std::optional<Token> bounds_at_, hi_at_, sigma_at_, sigma_value_at_, min_at_, max_at_, values_at_;
  bool in_values_ = false;
};

// ---------------------------------------------------------------------------------------------
// Diff helpers.

std::vector<std::string_view> split_lines(std::string_view text) {
  std::vector<std::string_view> lines;
  std::size_t start = 0;
  while (start < text.size()) {
    const std::size_t nl = text.find('\n', start);
    const std::size_t end = nl == std::string_view::npos ? text.size() : nl;
    lines.push_back(text.substr(start, end - start));
    start = end + 1;
  }
  return lines;
}

constexpr std::size_t kMaxDiffLines = 30;

void add_line(std::vector<std::string>& out, std::size_t& dropped, std::string line) {
  if (out.size() < kMaxDiffLines)
    out.push_back(std::move(line));
  else
    ++dropped;
}

// A line diff of two texts: common prefix and suffix stripped, the middle by longest common
// subsequence when small enough, else everything in the middle as removed then added.
void line_diff(std::string_view a_text, std::string_view b_text, std::vector<std::string>& out, std::size_t& dropped) {
  const auto a = split_lines(a_text), b = split_lines(b_text);
  std::size_t p = 0;
  while (p < a.size() && p < b.size() && a[p] == b[p]) ++p;
  std::size_t s = 0;
  while (s < a.size() - p && s < b.size() - p && a[a.size() - 1 - s] == b[b.size() - 1 - s]) ++s;
  const std::size_t n = a.size() - p - s, m = b.size() - p - s;
  auto removed = [&](std::size_t i) {
    add_line(out, dropped, "line " + std::to_string(i + 1) + ": - " + std::string(a[i]));
  };
  auto added = [&](std::size_t j) {
    add_line(out, dropped, "line " + std::to_string(j + 1) + ": + " + std::string(b[j]));
  };
  if (n * m > 4'000'000) {
    for (std::size_t i = 0; i < n; ++i) removed(p + i);
    for (std::size_t j = 0; j < m; ++j) added(p + j);
    return;
  }
  // lcs[i][j]: the longest common subsequence of a's middle from i and b's middle from j.
  std::vector<std::uint32_t> lcs((n + 1) * (m + 1), 0);
  auto cell = [&](std::size_t i, std::size_t j) -> std::uint32_t& { return lcs[i * (m + 1) + j]; };
  for (std::size_t i = n; i-- > 0;)
    for (std::size_t j = m; j-- > 0;)
      cell(i, j) = a[p + i] == b[p + j] ? cell(i + 1, j + 1) + 1 : std::max(cell(i + 1, j), cell(i, j + 1));
  std::size_t i = 0, j = 0;
  while (i < n || j < m) {
    if (i < n && j < m && a[p + i] == b[p + j]) {
      ++i;
      ++j;
    } else if (i < n && (j == m || cell(i + 1, j) >= cell(i, j + 1))) {
      removed(p + i++);  // removals before additions, as diff tools show a changed line
    } else {
      added(p + j++);
    }
  }
}

void real_diff(const RealGenome& a, const RealGenome& b, std::vector<std::string>& out, std::size_t& dropped) {
  auto changed = [&](const char* what, double x, double y) {
    if (!(x == y))
      add_line(out, dropped,
               std::string(what) + ": " + kernel::shortest_text<double>(x) + " -> " + kernel::shortest_text<double>(y));
  };
  if (!(a.lo == b.lo && a.hi == b.hi))
    add_line(out, dropped,
             "bounds: [" + kernel::shortest_text<double>(a.lo) + ", " + kernel::shortest_text<double>(a.hi) + "] -> [" +
                 kernel::shortest_text<double>(b.lo) + ", " + kernel::shortest_text<double>(b.hi) + "]");
  changed("sigma", a.sigma, b.sigma);
  changed("sigma min", a.sigma_min, b.sigma_min);
  changed("sigma max", a.sigma_max, b.sigma_max);
  if (a.values.size() != b.values.size())
    add_line(out, dropped, "length: " + std::to_string(a.values.size()) + " -> " + std::to_string(b.values.size()));
  const std::size_t common = std::min(a.values.size(), b.values.size());
  for (std::size_t i = 0; i < common; ++i)
    if (!(a.values[i] == b.values[i]))
      add_line(out, dropped,
               "value " + std::to_string(i) + ": " + kernel::shortest_text<double>(a.values[i]) + " -> " +
                   kernel::shortest_text<double>(b.values[i]));
}

bool coin(kernel::RandomStream& random) { return random.uniform() < 0.5; }

control::ahhs::Network ahhs_crossover(const control::ahhs::Network& a, const control::ahhs::Network& b,
                                      kernel::RandomStream& random) {
  if (!same_structure(a, b)) return a;
  control::ahhs::Network child = a;
  for (std::size_t i = 0; i < child.hormones.size(); ++i) {
    control::ahhs::Hormone& h = child.hormones[i];
    const control::ahhs::Hormone& o = b.hormones[i];
    if (coin(random)) h.base = o.base;
    if (coin(random)) h.decay = o.decay;
    if (coin(random)) h.diffusion = o.diffusion;
    if (coin(random)) {
      h.min = o.min;
      h.max = o.max;
      h.start = o.start;
    }
  }
  for (std::size_t i = 0; i < child.rules.size(); ++i) {
    control::ahhs::Rule& r = child.rules[i];
    const control::ahhs::Rule& o = b.rules[i];
    if (coin(random)) r.centre = o.centre;
    if (coin(random)) r.width = o.width;
    if (coin(random)) r.fixed = o.fixed;
    if (coin(random)) r.dependent = o.dependent;
  }
  // Each number comes from a valid network with the same structure (same degrees, so diffusion
  // limits hold); a parent that was itself invalid is the only way to fail here.
  if (!control::ahhs::validate(child)) return a;
  return child;
}

}  // namespace

GenomeKind kind_of(const Genome& g) { return static_cast<GenomeKind>(g.index()); }

const char* kind_name(GenomeKind k) {
  switch (k) {
    case GenomeKind::kReal: return "real";
    case GenomeKind::kAhhs: return "ahhs";
    case GenomeKind::kLinda: return "linda";
  }
  return "?";
}

kernel::Status check(const Genome& g) {
  if (const auto* r = std::get_if<RealGenome>(&g)) return check(*r);
  if (const auto* n = std::get_if<control::ahhs::Network>(&g)) return control::ahhs::validate(*n);
  return control::snn::check_genome(std::get<control::snn::Genome>(g));
}

kernel::Result<Genome> parse_genome_text(std::string_view text) {
  if (text.size() > kMaxGenomeTextBytes)
    return kernel::located_error({1, 1}, "genome text longer than " + std::to_string(kMaxGenomeTextBytes) + " bytes");
  RealParser real;
  std::optional<GenomeKind> kind;
  std::size_t line_number = 0, start = 0;
  std::string_view last_line;
  while (start <= text.size()) {
    const std::size_t nl = text.find('\n', start);
    const std::size_t end = nl == std::string_view::npos ? text.size() : nl;
    const std::string_view line = text.substr(start, end - start);
    ++line_number;
    last_line = line;
    start = end + 1;
    auto tokens = kernel::split_words(line, line_number);
    if (!tokens) return Error{tokens.error()};
    const std::vector<Token>& t = *tokens;
    if (!t.empty()) {
      if (kind) {
        if (auto st = real.statement(t); !st) return Error{st.error()};
      } else {
        if (t[0].text != "genome")
          return t[0].error("expected 'genome real|ahhs|linda' first, not '" + shown(t[0].text) + "'");
        if (t.size() < 2) return t[0].error_after("'genome' needs a kind: real, ahhs or linda");
        if (t[1].text == "real")
          kind = GenomeKind::kReal;
        else if (t[1].text == "ahhs")
          kind = GenomeKind::kAhhs;
        else if (t[1].text == "linda")
          kind = GenomeKind::kLinda;
        else
          return t[1].error("unknown genome kind '" + shown(t[1].text) + "' (real, ahhs or linda)");
        if (t.size() > 2) return t[2].error("nothing may follow 'genome " + std::string(t[1].text) + "' on its line");
        real.header_ = line_number;
        if (*kind != GenomeKind::kReal) {
          // Everything after this line is the controller's own description.
          const std::string_view embedded = start <= text.size() ? text.substr(start) : std::string_view();
          // Without a line break after the header there is no line for the embedded text's errors
          // to point at: they point just after the header.
          const bool ends_here = nl == std::string_view::npos;
          auto relocated = [&](const std::string& e) {
            return ends_here ? t.back().error_after(kernel::split_location(e).message) : Error{rebase(e, line_number)};
          };
          if (*kind == GenomeKind::kAhhs) {
            auto n = control::ahhs::parse_network(embedded);
            if (!n) return relocated(n.error());
            return Genome{std::move(n).value()};
          }
          auto g = control::snn::parse_genome(embedded);
          if (!g) return relocated(g.error());
          return Genome{std::move(g).value()};
        }
      }
    }
    if (nl == std::string_view::npos) break;
  }
  if (!kind)
    return Error{location_prefix(line_number, last_line.size() + 1) + "empty text: expected 'genome real|ahhs|linda'"};
  auto r = real.finish(line_number, last_line.size() + 1);
  if (!r) return Error{r.error()};
  return Genome{std::move(r).value()};
}

std::string to_text(const Genome& g) {
  std::string out = std::string("genome ") + kind_name(kind_of(g)) + "\n";
  if (const auto* n = std::get_if<control::ahhs::Network>(&g)) return out + control::ahhs::to_text(*n);
  if (const auto* l = std::get_if<control::snn::Genome>(&g)) return out + control::snn::to_text(*l);
  const RealGenome& r = std::get<RealGenome>(g);
  out += "bounds " + kernel::shortest_text<double>(r.lo) + " " + kernel::shortest_text<double>(r.hi) + "\n";
  out += "sigma " + kernel::shortest_text<double>(r.sigma) + " min " + kernel::shortest_text<double>(r.sigma_min) +
         " max " + kernel::shortest_text<double>(r.sigma_max) + "\n";
  out += "values";
  for (std::size_t i = 0; i < r.values.size(); ++i) {
    out += i > 0 && i % 8 == 0 ? "\n  " : " ";
    out += kernel::shortest_text<double>(r.values[i]);
  }
  out += "\n";
  return out;
}

std::vector<std::string> diff(const Genome& a, const Genome& b) {
  std::vector<std::string> out;
  if (a == b) return out;
  std::size_t dropped = 0;
  if (a.index() != b.index()) {
    out.push_back(std::string("kind: ") + kind_name(kind_of(a)) + " -> " + kind_name(kind_of(b)));
  } else if (const auto* ra = std::get_if<RealGenome>(&a)) {
    real_diff(*ra, std::get<RealGenome>(b), out, dropped);
  } else {
    line_diff(to_text(a), to_text(b), out, dropped);
  }
  // Unequal genomes whose texts agree (a NaN somewhere compares unequal to itself).
  if (out.empty() && dropped == 0) out.push_back("numbers differ that the text form cannot show (not finite)");
  if (dropped > 0) out.push_back("... and " + std::to_string(dropped) + " more");
  return out;
}

void mutate(Genome& g, kernel::RandomStream& random, const GenomeMutation& options) {
  if (auto* r = std::get_if<RealGenome>(&g)) {
    mutate_sigma_lognormal(*r, random);
    mutate_gaussian(*r, random);
  } else if (auto* n = std::get_if<control::ahhs::Network>(&g)) {
    control::ahhs::mutate(*n, random, options.ahhs);
  } else {
    control::snn::mutate(std::get<control::snn::Genome>(g), random, options.linda);
  }
}

Genome crossover(const Genome& a, const Genome& b, kernel::RandomStream& random) {
  if (a.index() != b.index()) return a;
  if (const auto* r = std::get_if<RealGenome>(&a)) return crossover_uniform(*r, std::get<RealGenome>(b), random);
  if (const auto* n = std::get_if<control::ahhs::Network>(&a))
    return ahhs_crossover(*n, std::get<control::ahhs::Network>(b), random);
  return control::snn::crossover(std::get<control::snn::Genome>(a), std::get<control::snn::Genome>(b), random);
}

bool same_structure(const control::ahhs::Network& a, const control::ahhs::Network& b) {
  if (a.compartments != b.compartments || a.links != b.links || a.sensors != b.sensors || a.actuators != b.actuators)
    return false;
  if (a.hormones.size() != b.hormones.size() || a.rules.size() != b.rules.size()) return false;
  for (std::size_t i = 0; i < a.hormones.size(); ++i)
    if (a.hormones[i].name != b.hormones[i].name) return false;
  for (std::size_t i = 0; i < a.rules.size(); ++i) {
    const control::ahhs::Rule &x = a.rules[i], &y = b.rules[i];
    if (x.kind != y.kind || x.source != y.source || x.target != y.target || x.compartment != y.compartment)
      return false;
  }
  return true;
}

}  // namespace symb::evo
