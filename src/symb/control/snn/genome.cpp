#include "symb/control/snn/genome.hpp"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "symb/control/snn/development.hpp"
#include "symb/control/snn/spiking_network.hpp"
#include "symb/kernel/source_text.hpp"

namespace symb::control::snn {

using kernel::Error;

namespace {

// Limits of the text form (genome.hpp).
constexpr std::size_t kMaxGenomeLineLength = 1024;
constexpr std::size_t kMaxNameLength = 32;
constexpr float kMaxDiffusion = 0.25f;                  // the explicit 5-point scheme is stable up to 1/4
constexpr std::int64_t kMaxSiteCoordinate = 1'000'000;  // beyond: "out of range" rather than "outside"

using Token = kernel::TextToken;
using kernel::location_prefix;

std::string quoted(std::string_view s) { return "'" + std::string(s) + "'"; }

const char* direction_name(Direction d) {
  switch (d) {
    case Direction::kNorth: return "north";
    case Direction::kSouth: return "south";
    case Direction::kEast: return "east";
    case Direction::kWest: return "west";
    case Direction::kUp: return "up";
    case Direction::kDown: return "down";
  }
  return "north";
}

const char* action_name(ActionKind a) {
  switch (a) {
    case ActionKind::kSecrete: return "secrete";
    case ActionKind::kMove: return "move";
    case ActionKind::kDivide: return "divide";
    case ActionKind::kDie: return "die";
    case ActionKind::kGrow: return "grow";
    case ActionKind::kPrune: return "prune";
    case ActionKind::kWeight: return "weight";
    case ActionKind::kBias: return "bias";
    case ActionKind::kClass: return "class";
  }
  return "secrete";
}

class Parser {
 public:
  explicit Parser(std::string_view text) : text_(text) {}

  kernel::Result<Genome> run() {
    std::size_t line = 1;
    std::size_t pos = 0;
    while (pos <= text_.size()) {
      std::size_t end = text_.find('\n', pos);
      if (end == std::string_view::npos) end = text_.size();
      const std::string_view row = text_.substr(pos, end - pos);
      if (row.size() > kMaxGenomeLineLength)
        return Error{location_prefix(line, kMaxGenomeLineLength + 1) + "line longer than " +
                     std::to_string(kMaxGenomeLineLength) + " characters"};
      auto words = kernel::split_words(row, line);
      if (!words) return Error{words.error()};
      const std::vector<Token>& tokens = *words;
      if (!tokens.empty()) {
        if (auto st = statement(tokens); !st) return Error{st.error()};
      }
      end_ = {std::string_view(), line, row.size() + 1};
      if (end == text_.size()) break;
      pos = end + 1;
      ++line;
    }
    return finish();
  }

 private:
  using Tokens = std::vector<Token>;

  kernel::Status statement(const Tokens& s) {
    const std::string_view kw = s[0].text;
    if (kw == "grid") return grid(s);
    if (kw == "ticks") return whole_setting(s, have_ticks_, genome_.ticks, kMaxTicks, "ticks N");
    if (kw == "warmup") return whole_setting(s, have_warmup_, genome_.warmup, kMaxTicks, "warmup N");
    if (kw == "noise") return real_setting(s, have_noise_, genome_.noise, 0, kMaxGenomeNumber, "noise A");
    if (kw == "reach") return real_setting(s, have_reach_, genome_.reach, 0, kMaxGenomeNumber, "reach R");
    if (kw == "integration") return integration(s);
    if (kw == "morphogen") return morphogen(s);
    if (kw == "source") return source(s);
    if (kw == "seed") return seed(s);
    if (kw == "input" || kw == "output") return channel(s);
    if (kw == "gene") return gene(s);
    return s[0].error("unknown statement " + quoted(kw) +
                      " (grid, ticks, warmup, noise, integration, reach, morphogen, source, seed, input, "
                      "output or gene)");
  }

  // The token at index i, or an error right after the statement's last token.
  kernel::Result<Token> at(const Tokens& s, std::size_t i, const char* shape) {
    if (i < s.size()) return s[i];
    const Token& last = s.back();
    return last.error_after(std::string("incomplete: ") + shape);
  }

  kernel::Status no_more(const Tokens& s, std::size_t n, const char* shape) {
    if (s.size() > n) return s[n].error("unexpected " + quoted(s[n].text) + " after the statement: " + shape);
    return {};
  }

  kernel::Status keyword(const Tokens& s, std::size_t i, std::string_view word, const char* shape) {
    auto t = at(s, i, shape);
    if (!t) return Error{t.error()};
    if (t->text != word) return t->error("expected " + quoted(word) + ", got " + quoted(t->text) + ": " + shape);
    return {};
  }

  kernel::Result<int> whole(const Tokens& s, std::size_t i, std::int64_t lo, std::int64_t hi, const char* what,
                            const char* shape) {
    auto t = at(s, i, shape);
    if (!t) return Error{t.error()};
    std::int64_t v = 0;
    const char* first = t->text.data();
    const char* last = first + t->text.size();
    auto [p, ec] = std::from_chars(first, last, v);
    if (ec == std::errc::result_out_of_range && p == last)
      return t->error(std::string(what) + " out of range " + std::to_string(lo) + ".." + std::to_string(hi));
    if (ec != std::errc() || p != last)
      return t->error(std::string(what) + " must be a whole number, got " + quoted(t->text));
    if (v < lo || v > hi)
      return t->error(std::string(what) + " " + std::string(t->text) + " out of range " + std::to_string(lo) + ".." +
                      std::to_string(hi));
    return static_cast<int>(v);
  }

  static kernel::Result<float> real_of(const Token& t, std::string_view text, float lo, float hi, const char* what) {
    float v = 0;
    const char* first = text.data();
    const char* last = first + text.size();
    auto [p, ec] = std::from_chars(first, last, v);
    if (ec == std::errc::result_out_of_range && p == last)
      return t.error(std::string(what) + " " + quoted(text) + " out of range " + kernel::shortest_text<float>(lo) +
                     ".." + kernel::shortest_text<float>(hi));
    if (ec != std::errc() || p != last || !std::isfinite(v))
      return t.error(std::string(what) + " must be a decimal number, got " + quoted(text));
    if (v < lo || v > hi)
      return t.error(std::string(what) + " " + std::string(text) + " out of range " + kernel::shortest_text<float>(lo) +
                     ".." + kernel::shortest_text<float>(hi));
    return v;
  }

  kernel::Result<float> real(const Tokens& s, std::size_t i, float lo, float hi, const char* what, const char* shape) {
    auto t = at(s, i, shape);
    if (!t) return Error{t.error()};
    return real_of(*t, t->text, lo, hi, what);
  }

  kernel::Result<int> morphogen_ref(const Token& t, std::string_view name) {
    for (std::size_t m = 0; m < genome_.morphogens.size(); ++m)
      if (genome_.morphogens[m].name == name) return static_cast<int>(m);
    return t.error("no morphogen named " + quoted(name) + " declared above");
  }

  kernel::Result<int> morphogen_at(const Tokens& s, std::size_t i, const char* shape) {
    auto t = at(s, i, shape);
    if (!t) return Error{t.error()};
    return morphogen_ref(*t, t->text);
  }

  kernel::Result<NeuronClass> neuron_class(const Tokens& s, std::size_t i, const char* shape) {
    auto t = at(s, i, shape);
    if (!t) return Error{t.error()};
    auto c = parse_neuron_class(t->text);
    if (!c) return t->error("unknown neuron class " + quoted(t->text) + " (RS, IB, CH, FS, LTS, TC or RZ)");
    return *c;
  }

  // X Y at s[i], s[i+1]: a site inside the grid.
  kernel::Status site(const Tokens& s, std::size_t i, int& x, int& y, const char* shape) {
    if (!have_grid_) {
      auto t = at(s, i, shape);
      if (!t) return Error{t.error()};
      return t->error("a site before the grid: write 'grid W H' first");
    }
    auto vx = whole(s, i, -kMaxSiteCoordinate, kMaxSiteCoordinate, "x", shape);
    if (!vx) return Error{vx.error()};
    if (*vx < 0 || *vx >= genome_.width)
      return s[i].error("x " + std::to_string(*vx) + " outside the grid (0.." + std::to_string(genome_.width - 1) +
                        ")");
    auto vy = whole(s, i + 1, -kMaxSiteCoordinate, kMaxSiteCoordinate, "y", shape);
    if (!vy) return Error{vy.error()};
    if (*vy < 0 || *vy >= genome_.height)
      return (s[i + 1]).error("y " + std::to_string(*vy) + " outside the grid (0.." +
                              std::to_string(genome_.height - 1) + ")");
    x = *vx;
    y = *vy;
    return {};
  }

  kernel::Status duplicate(const Token& t, bool& seen) {
    if (seen) return t.error("duplicate " + quoted(t.text) + " statement");
    seen = true;
    return {};
  }

  kernel::Status grid(const Tokens& s) {
    const char* shape = "grid W H";
    if (auto st = duplicate(s[0], have_grid_); !st) return st;
    auto w = whole(s, 1, 1, kMaxGridSide, "width", shape);
    if (!w) return Error{w.error()};
    auto h = whole(s, 2, 1, kMaxGridSide, "height", shape);
    if (!h) return Error{h.error()};
    genome_.width = *w;
    genome_.height = *h;
    return no_more(s, 3, shape);
  }

  kernel::Status whole_setting(const Tokens& s, bool& seen, int& out, int hi, const char* shape) {
    if (auto st = duplicate(s[0], seen); !st) return st;
    auto v = whole(s, 1, 0, hi, "a tick count", shape);
    if (!v) return Error{v.error()};
    out = *v;
    return no_more(s, 2, shape);
  }

  kernel::Status real_setting(const Tokens& s, bool& seen, float& out, float lo, float hi, const char* shape) {
    if (auto st = duplicate(s[0], seen); !st) return st;
    auto v = real(s, 1, lo, hi, "the value", shape);
    if (!v) return Error{v.error()};
    out = *v;
    return no_more(s, 2, shape);
  }

  kernel::Status integration(const Tokens& s) {
    const char* shape = "integration published|euler";
    if (auto st = duplicate(s[0], have_integration_); !st) return st;
    auto t = at(s, 1, shape);
    if (!t) return Error{t.error()};
    auto i = parse_integration(t->text);
    if (!i) return t->error("unknown integration " + quoted(t->text) + " (published or euler)");
    genome_.integration = *i;
    return no_more(s, 2, shape);
  }

  kernel::Status morphogen(const Tokens& s) {
    const char* shape = "morphogen NAME diffusion D decay L";
    auto name = at(s, 1, shape);
    if (!name) return Error{name.error()};
    if (name->text.size() > kMaxNameLength)
      return name->error("name longer than " + std::to_string(kMaxNameLength) + " characters");
    if (!kernel::is_identifier(name->text))
      return name->error("a morphogen name is [A-Za-z_][A-Za-z0-9_]*, got " + quoted(name->text));
    for (const auto& m : genome_.morphogens)
      if (m.name == name->text) return name->error("duplicate morphogen " + quoted(name->text));
    if (genome_.morphogens.size() >= kMaxMorphogens)
      return s[0].error("too many morphogens (at most " + std::to_string(kMaxMorphogens) + ")");
    Morphogen m;
    m.name = std::string(name->text);
    if (auto st = keyword(s, 2, "diffusion", shape); !st) return st;
    auto d = real(s, 3, 0, kMaxDiffusion, "diffusion", shape);
    if (!d) return Error{d.error()};
    if (auto st = keyword(s, 4, "decay", shape); !st) return st;
    auto l = real(s, 5, 0, 1, "decay", shape);
    if (!l) return Error{l.error()};
    m.diffusion = *d;
    m.decay = *l;
    if (auto st = no_more(s, 6, shape); !st) return st;
    genome_.morphogens.push_back(std::move(m));
    return {};
  }

  kernel::Status source(const Tokens& s) {
    const char* shape = "source NAME at X Y rate R";
    if (genome_.sources.size() >= kMaxSites)
      return s[0].error("too many sources (at most " + std::to_string(kMaxSites) + ")");
    Source src;
    auto m = morphogen_at(s, 1, shape);
    if (!m) return Error{m.error()};
    src.morphogen = *m;
    if (auto st = keyword(s, 2, "at", shape); !st) return st;
    if (auto st = site(s, 3, src.x, src.y, shape); !st) return st;
    if (auto st = keyword(s, 5, "rate", shape); !st) return st;
    auto r = real(s, 6, -kMaxGenomeNumber, kMaxGenomeNumber, "rate", shape);
    if (!r) return Error{r.error()};
    src.rate = *r;
    if (auto st = no_more(s, 7, shape); !st) return st;
    genome_.sources.push_back(src);
    return {};
  }

  kernel::Status seed(const Tokens& s) {
    const char* shape = "seed at X Y class C [bias B]";
    if (genome_.seeds.size() >= kMaxSites)
      return s[0].error("too many seeds (at most " + std::to_string(kMaxSites) + ")");
    SeedCell c;
    if (auto st = keyword(s, 1, "at", shape); !st) return st;
    if (auto st = site(s, 2, c.x, c.y, shape); !st) return st;
    for (const auto& other : genome_.seeds)
      if (other.x == c.x && other.y == c.y)
        return s[2].error("duplicate seed site (" + std::to_string(c.x) + ", " + std::to_string(c.y) + ")");
    if (auto st = keyword(s, 4, "class", shape); !st) return st;
    auto cls = neuron_class(s, 5, shape);
    if (!cls) return Error{cls.error()};
    c.cls = *cls;
    std::size_t n = 6;
    if (s.size() > 6 && s[6].text == "bias") {
      auto b = real(s, 7, -kMaxAbsBias, kMaxAbsBias, "bias", shape);
      if (!b) return Error{b.error()};
      c.bias = *b;
      n = 8;
    }
    if (auto st = no_more(s, n, shape); !st) return st;
    genome_.seeds.push_back(c);
    return {};
  }

  kernel::Status channel(const Tokens& s) {
    const bool input = s[0].text == "input";
    const char* shape = input ? "input K at X Y" : "output K at X Y";
    auto& list = input ? genome_.inputs : genome_.outputs;
    if (list.size() >= kMaxSites)
      return s[0].error(std::string("too many ") + (input ? "inputs" : "outputs") + " (at most " +
                        std::to_string(kMaxSites) + ")");
    ChannelSite c;
    auto k = whole(s, 1, 0, kMaxChannels - 1, "channel", shape);
    if (!k) return Error{k.error()};
    c.channel = *k;
    if (auto st = keyword(s, 2, "at", shape); !st) return st;
    if (auto st = site(s, 3, c.x, c.y, shape); !st) return st;
    if (auto st = no_more(s, 5, shape); !st) return st;
    list.push_back(c);
    return {};
  }

  kernel::Status gene(const Tokens& s) {
    const char* shape = "gene [once] [class C] when B [W*NAME ...] do ACTION";
    if (genome_.genes.size() >= kMaxGenes)
      return s[0].error("too many genes (at most " + std::to_string(kMaxGenes) + ")");
    Gene g;
    std::size_t i = 1;
    if (i < s.size() && s[i].text == "once") {
      g.once = true;
      ++i;
    }
    if (i < s.size() && s[i].text == "class") {
      auto c = neuron_class(s, i + 1, shape);
      if (!c) return Error{c.error()};
      g.only = *c;
      i += 2;
    }
    if (auto st = keyword(s, i, "when", shape); !st) return st;
    auto b = real(s, i + 1, -kMaxGenomeNumber, kMaxGenomeNumber, "the gene's bias", shape);
    if (!b) return Error{b.error()};
    g.bias = *b;
    i += 2;
    while (i < s.size() && s[i].text != "do") {
      const Token& t = s[i];
      const std::size_t star = t.text.find('*');
      if (star == std::string_view::npos)
        return t.error("expected a term W*NAME or 'do', got " + quoted(t.text) + ": " + shape);
      if (g.terms.size() >= kMaxTerms)
        return t.error("too many terms (at most " + std::to_string(kMaxTerms) + " a gene)");
      auto w = real_of(t, t.text.substr(0, star), -kMaxGenomeNumber, kMaxGenomeNumber, "a term's weight");
      if (!w) return Error{w.error()};
      Token name_token{t.text.substr(star + 1), t.line, t.column + star + 1};
      auto m = morphogen_ref(name_token, name_token.text);
      if (!m) return Error{m.error()};
      g.terms.push_back({*m, *w});
      ++i;
    }
    if (auto st = keyword(s, i, "do", shape); !st) return st;
    return action(s, i + 1, g);
  }

  // DIR at s[i]: sets g.direction (and g.morphogen for up/down); returns the index after it.
  kernel::Result<std::size_t> direction(const Tokens& s, std::size_t i, Gene& g, const char* shape) {
    auto t = at(s, i, shape);
    if (!t) return Error{t.error()};
    const std::string_view d = t->text;
    if (d == "north")
      g.direction = Direction::kNorth;
    else if (d == "south")
      g.direction = Direction::kSouth;
    else if (d == "east")
      g.direction = Direction::kEast;
    else if (d == "west")
      g.direction = Direction::kWest;
    else if (d == "up" || d == "down") {
      g.direction = d == "up" ? Direction::kUp : Direction::kDown;
      auto m = morphogen_at(s, i + 1, shape);
      if (!m) return Error{m.error()};
      g.morphogen = *m;
      return i + 2;
    } else {
      return t->error("unknown direction " + quoted(d) + " (north, south, east, west, up NAME or down NAME)");
    }
    return i + 1;
  }

  kernel::Status action(const Tokens& s, std::size_t i, Gene g) {
    auto t = at(s, i, "... do ACTION");
    if (!t) return Error{t.error()};
    const std::string_view a = t->text;
    std::size_t n = i + 1;
    const char* shape = "";
    if (a == "secrete") {
      shape = "secrete NAME AMOUNT";
      g.action = ActionKind::kSecrete;
      auto m = morphogen_at(s, i + 1, shape);
      if (!m) return Error{m.error()};
      g.morphogen = *m;
      auto v = real(s, i + 2, -kMaxGenomeNumber, kMaxGenomeNumber, "the amount", shape);
      if (!v) return Error{v.error()};
      g.amount = *v;
      n = i + 3;
    } else if (a == "move") {
      shape = "move north|south|east|west|up NAME|down NAME";
      g.action = ActionKind::kMove;
      auto next = direction(s, i + 1, g, shape);
      if (!next) return Error{next.error()};
      n = *next;
    } else if (a == "divide") {
      shape = "divide DIR CLASS";
      g.action = ActionKind::kDivide;
      auto next = direction(s, i + 1, g, shape);
      if (!next) return Error{next.error()};
      auto c = neuron_class(s, *next, shape);
      if (!c) return Error{c.error()};
      g.cls = *c;
      n = *next + 1;
    } else if (a == "die") {
      shape = "die";
      g.action = ActionKind::kDie;
    } else if (a == "grow") {
      shape = "grow up|down NAME weight W delay D";
      g.action = ActionKind::kGrow;
      auto d = at(s, i + 1, shape);
      if (!d) return Error{d.error()};
      if (d->text != "up" && d->text != "down")
        return d->error("expected 'up' or 'down', got " + quoted(d->text) + ": " + shape);
      g.direction = d->text == "up" ? Direction::kUp : Direction::kDown;
      auto m = morphogen_at(s, i + 2, shape);
      if (!m) return Error{m.error()};
      g.morphogen = *m;
      if (auto st = keyword(s, i + 3, "weight", shape); !st) return st;
      auto w = real(s, i + 4, -kMaxGrownWeight, kMaxGrownWeight, "the weight", shape);
      if (!w) return Error{w.error()};
      g.amount = *w;
      if (auto st = keyword(s, i + 5, "delay", shape); !st) return st;
      auto delay = whole(s, i + 6, 0, kMaxDelay, "the delay", shape);
      if (!delay) return Error{delay.error()};
      g.delay = *delay;
      n = i + 7;
    } else if (a == "prune") {
      shape = "prune";
      g.action = ActionKind::kPrune;
    } else if (a == "weight") {
      shape = "weight DELTA";
      g.action = ActionKind::kWeight;
      auto v = real(s, i + 1, -kMaxGenomeNumber, kMaxGenomeNumber, "the delta", shape);
      if (!v) return Error{v.error()};
      g.amount = *v;
      n = i + 2;
    } else if (a == "bias") {
      shape = "bias VALUE";
      g.action = ActionKind::kBias;
      auto v = real(s, i + 1, -kMaxAbsBias, kMaxAbsBias, "the bias", shape);
      if (!v) return Error{v.error()};
      g.amount = *v;
      n = i + 2;
    } else if (a == "class") {
      shape = "class C";
      g.action = ActionKind::kClass;
      auto c = neuron_class(s, i + 1, shape);
      if (!c) return Error{c.error()};
      g.cls = *c;
      n = i + 2;
    } else {
      return t->error("unknown action " + quoted(a) +
                      " (secrete, move, divide, die, grow, prune, weight, bias or class)");
    }
    if (auto st = no_more(s, n, shape); !st) return st;
    genome_.genes.push_back(std::move(g));
    return {};
  }

  kernel::Result<Genome> finish() {
    if (!have_grid_) return end_.error("missing 'grid W H'");
    if (genome_.seeds.empty()) return end_.error("missing a seed cell ('seed at X Y class C')");
    if (auto st = check_genome(genome_); !st) return end_.error(st.error());
    return std::move(genome_);
  }

  std::string_view text_;
  Token end_;
  Genome genome_;
  bool have_grid_ = false, have_ticks_ = false, have_warmup_ = false, have_noise_ = false, have_reach_ = false,
       have_integration_ = false;
};

bool within(float v, float lo, float hi) { return std::isfinite(v) && v >= lo && v <= hi; }

std::string item(const char* what, std::size_t i) { return std::string(what) + " " + std::to_string(i) + ": "; }

}  // namespace

kernel::Result<Genome> parse_genome(std::string_view text) { return Parser(text).run(); }

std::string to_text(const Genome& g) {
  std::string out;
  auto name = [&](int m) -> std::string {
    if (m < 0 || static_cast<std::size_t>(m) >= g.morphogens.size()) return "?";
    return g.morphogens[static_cast<std::size_t>(m)].name;
  };
  out += "grid " + std::to_string(g.width) + " " + std::to_string(g.height) + "\n";
  out += "ticks " + std::to_string(g.ticks) + "\n";
  out += "warmup " + std::to_string(g.warmup) + "\n";
  out += "noise " + kernel::shortest_text<float>(g.noise) + "\n";
  out += std::string("integration ") + to_string(g.integration) + "\n";
  out += "reach " + kernel::shortest_text<float>(g.reach) + "\n";
  for (const auto& m : g.morphogens)
    out += "morphogen " + m.name + " diffusion " + kernel::shortest_text<float>(m.diffusion) + " decay " +
           kernel::shortest_text<float>(m.decay) + "\n";
  for (const auto& s : g.sources)
    out += "source " + name(s.morphogen) + " at " + std::to_string(s.x) + " " + std::to_string(s.y) + " rate " +
           kernel::shortest_text<float>(s.rate) + "\n";
  for (const auto& c : g.seeds)
    out += "seed at " + std::to_string(c.x) + " " + std::to_string(c.y) + " class " + to_string(c.cls) + " bias " +
           kernel::shortest_text<float>(c.bias) + "\n";
  for (const auto& c : g.inputs)
    out += "input " + std::to_string(c.channel) + " at " + std::to_string(c.x) + " " + std::to_string(c.y) + "\n";
  for (const auto& c : g.outputs)
    out += "output " + std::to_string(c.channel) + " at " + std::to_string(c.x) + " " + std::to_string(c.y) + "\n";
  for (const auto& gene : g.genes) {
    out += "gene ";
    if (gene.once) out += "once ";
    if (gene.only) out += std::string("class ") + to_string(*gene.only) + " ";
    out += "when " + kernel::shortest_text<float>(gene.bias);
    for (const auto& t : gene.terms) out += " " + kernel::shortest_text<float>(t.weight) + "*" + name(t.morphogen);
    out += std::string(" do ") + action_name(gene.action);
    auto dir = [&] {
      out += std::string(" ") + direction_name(gene.direction);
      if (gene.direction == Direction::kUp || gene.direction == Direction::kDown) out += " " + name(gene.morphogen);
    };
    switch (gene.action) {
      case ActionKind::kSecrete:
        out += " " + name(gene.morphogen) + " " + kernel::shortest_text<float>(gene.amount);
        break;
      case ActionKind::kMove: dir(); break;
      case ActionKind::kDivide:
        dir();
        out += std::string(" ") + to_string(gene.cls);
        break;
      case ActionKind::kDie:
      case ActionKind::kPrune: break;
      case ActionKind::kGrow:
        out += std::string(" ") + direction_name(gene.direction) + " " + name(gene.morphogen) + " weight " +
               kernel::shortest_text<float>(gene.amount) + " delay " + std::to_string(gene.delay);
        break;
      case ActionKind::kWeight:
      case ActionKind::kBias: out += " " + kernel::shortest_text<float>(gene.amount); break;
      case ActionKind::kClass: out += std::string(" ") + to_string(gene.cls); break;
    }
    out += "\n";
  }
  return out;
}

kernel::Status check_genome(const Genome& g) {
  if (g.width < 1 || g.width > kMaxGridSide || g.height < 1 || g.height > kMaxGridSide)
    return Error{"grid " + std::to_string(g.width) + "x" + std::to_string(g.height) + " outside 1.." +
                 std::to_string(kMaxGridSide)};
  if (g.ticks < 0 || g.ticks > kMaxTicks) return Error{"ticks out of range 0.." + std::to_string(kMaxTicks)};
  if (g.warmup < 0 || g.warmup > kMaxTicks) return Error{"warmup out of range 0.." + std::to_string(kMaxTicks)};
  if (!within(g.noise, 0, kMaxGenomeNumber)) return Error{"noise out of range"};
  if (!within(g.reach, 0, kMaxGenomeNumber)) return Error{"reach out of range"};
  if (g.integration != Integration::kPublished && g.integration != Integration::kEuler)
    return Error{"unknown integration"};
  const int morphogens = static_cast<int>(g.morphogens.size());
  if (g.morphogens.size() > kMaxMorphogens) return Error{"more than " + std::to_string(kMaxMorphogens) + " morphogens"};
  for (std::size_t i = 0; i < g.morphogens.size(); ++i) {
    const auto& m = g.morphogens[i];
    if (m.name.size() > kMaxNameLength || !kernel::is_identifier(m.name))
      return Error{item("morphogen", i) + "bad name"};
    for (std::size_t j = 0; j < i; ++j)
      if (g.morphogens[j].name == m.name) return Error{item("morphogen", i) + "duplicate name " + quoted(m.name)};
    if (!within(m.diffusion, 0, kMaxDiffusion)) return Error{item("morphogen", i) + "diffusion out of range"};
    if (!within(m.decay, 0, 1)) return Error{item("morphogen", i) + "decay out of range"};
  }
  auto inside = [&](int x, int y) { return x >= 0 && x < g.width && y >= 0 && y < g.height; };
  auto valid_class = [](NeuronClass c) { return static_cast<int>(c) < kNeuronClassCount; };
  if (g.sources.size() > kMaxSites) return Error{"too many sources"};
  for (std::size_t i = 0; i < g.sources.size(); ++i) {
    const auto& s = g.sources[i];
    if (s.morphogen < 0 || s.morphogen >= morphogens) return Error{item("source", i) + "no such morphogen"};
    if (!inside(s.x, s.y)) return Error{item("source", i) + "site outside the grid"};
    if (!within(s.rate, -kMaxGenomeNumber, kMaxGenomeNumber)) return Error{item("source", i) + "rate out of range"};
  }
  if (g.seeds.empty()) return Error{"no seed cell"};
  if (g.seeds.size() > kMaxSites) return Error{"too many seeds"};
  for (std::size_t i = 0; i < g.seeds.size(); ++i) {
    const auto& c = g.seeds[i];
    if (!inside(c.x, c.y)) return Error{item("seed", i) + "site outside the grid"};
    for (std::size_t j = 0; j < i; ++j)
      if (g.seeds[j].x == c.x && g.seeds[j].y == c.y) return Error{item("seed", i) + "duplicate seed site"};
    if (!valid_class(c.cls)) return Error{item("seed", i) + "unknown class"};
    if (!within(c.bias, -kMaxAbsBias, kMaxAbsBias)) return Error{item("seed", i) + "bias out of range"};
  }
  for (const auto* list : {&g.inputs, &g.outputs}) {
    const char* what = list == &g.inputs ? "input" : "output";
    if (list->size() > kMaxSites) return Error{std::string("too many ") + what + "s"};
    for (std::size_t i = 0; i < list->size(); ++i) {
      const auto& c = (*list)[i];
      if (c.channel < 0 || c.channel >= kMaxChannels) return Error{item(what, i) + "channel out of range"};
      if (!inside(c.x, c.y)) return Error{item(what, i) + "site outside the grid"};
    }
  }
  if (g.genes.size() > kMaxGenes) return Error{"too many genes"};
  for (std::size_t i = 0; i < g.genes.size(); ++i) {
    const Gene& gene = g.genes[i];
    const std::string at = item("gene", i);
    if (gene.only && !valid_class(*gene.only)) return Error{at + "unknown class"};
    if (!within(gene.bias, -kMaxGenomeNumber, kMaxGenomeNumber)) return Error{at + "bias out of range"};
    if (gene.terms.size() > kMaxTerms) return Error{at + "too many terms"};
    for (const auto& t : gene.terms) {
      if (t.morphogen < 0 || t.morphogen >= morphogens) return Error{at + "a term names no morphogen"};
      if (!within(t.weight, -kMaxGenomeNumber, kMaxGenomeNumber)) return Error{at + "a term's weight out of range"};
    }
    // What each action uses; every other field must hold its default so that the text form, which
    // does not write them, gives the same genome back.
    bool uses_direction = false, uses_morphogen = false, uses_class = false, uses_amount = false, uses_delay = false;
    float lo = -kMaxGenomeNumber, hi = kMaxGenomeNumber;
    switch (gene.action) {
      case ActionKind::kSecrete: uses_morphogen = uses_amount = true; break;
      case ActionKind::kMove:
        uses_direction = true;
        uses_morphogen = gene.direction == Direction::kUp || gene.direction == Direction::kDown;
        break;
      case ActionKind::kDivide:
        uses_direction = uses_class = true;
        uses_morphogen = gene.direction == Direction::kUp || gene.direction == Direction::kDown;
        break;
      case ActionKind::kDie:
      case ActionKind::kPrune: break;
      case ActionKind::kGrow:
        if (gene.direction != Direction::kUp && gene.direction != Direction::kDown)
          return Error{at + "grow goes up or down a gradient"};
        uses_direction = uses_morphogen = uses_amount = uses_delay = true;
        lo = -kMaxGrownWeight;
        hi = kMaxGrownWeight;
        break;
      case ActionKind::kWeight: uses_amount = true; break;
      case ActionKind::kBias:
        uses_amount = true;
        lo = -kMaxAbsBias;
        hi = kMaxAbsBias;
        break;
      case ActionKind::kClass: uses_class = true; break;
      default: return Error{at + "unknown action"};
    }
    if (static_cast<int>(gene.direction) > static_cast<int>(Direction::kDown)) return Error{at + "unknown direction"};
    if (!valid_class(gene.cls)) return Error{at + "unknown class"};
    if (uses_morphogen && (gene.morphogen < 0 || gene.morphogen >= morphogens)) return Error{at + "names no morphogen"};
    if (uses_amount && !within(gene.amount, lo, hi)) return Error{at + "number out of range"};
    if (uses_delay && (gene.delay < 0 || gene.delay > static_cast<int>(kMaxDelay)))
      return Error{at + "delay out of range"};
    if ((!uses_direction && gene.direction != Direction::kNorth) || (!uses_morphogen && gene.morphogen != -1) ||
        (!uses_class && gene.cls != NeuronClass::kRS) || (!uses_amount && gene.amount != 0) ||
        (!uses_delay && gene.delay != 0))
      return Error{at + std::string("a field ") + action_name(gene.action) +
                   " does not use is not at its default (direction north, morphogen -1, class RS, 0)"};
  }
  return {};
}

}  // namespace symb::control::snn
