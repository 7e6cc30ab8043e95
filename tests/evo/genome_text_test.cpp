// The unified genome's text form (genome.hpp): exact round trips of each kind (and of 200 mutants
// each), malformed texts with their exact locations (errors inside embedded ahhs and linda
// descriptions rebased to the whole file), 1,000 token-level mutants of valid texts, diff output,
// and the operators' dispatch.
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "symb/control/ahhs/parser.hpp"
#include "symb/evo/genome/genome.hpp"
#include "symb/kernel/random_stream.hpp"

namespace symb::evo {
namespace {

std::string read_shipped(const std::string& relative) {
  std::ifstream in(std::string(SYMB_SHIPPED_SCENARIO_DIR) + "/" + relative);
  EXPECT_TRUE(in.good()) << relative;
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

Genome must_parse(const std::string& text) {
  auto r = parse_genome_text(text);
  EXPECT_TRUE(r.ok()) << (r ? "" : r.error()) << "\n" << text;
  return r ? *r : Genome{};
}

std::string ahhs_text() { return "# the shipped avoider\ngenome ahhs\n" + read_shipped("ahhs/two_hormone.ahhs"); }
std::string linda_text() { return "genome linda\n" + read_shipped("linda/avoider.genome"); }
std::string real_text() {
  return "# a perceptron's 16 weights\n"
         "genome real\n"
         "bounds -4 4\n"
         "sigma 0.5 min 0.001 max 4   # step size\n"
         "values 0.5 -0.25 1 2 3 -4 4 0\n"
         "  0.125 1e-3 -1e-310 3.999999999999999 0.1 0.2 0.3 -0.3\n";
}

void expect_round_trip(const Genome& g) {
  ASSERT_TRUE(check(g).ok()) << check(g).error();
  const std::string text = to_text(g);
  auto back = parse_genome_text(text);
  ASSERT_TRUE(back.ok()) << back.error() << "\n" << text;
  EXPECT_TRUE(*back == g) << text;
  EXPECT_EQ(to_text(*back), text);
  EXPECT_TRUE(diff(g, *back).empty());
}

// "LINE:COLUMN: message" with LINE within the text (or just past its end).
bool located_within(const std::string& e, const std::string& text) {
  std::size_t i = 0, line = 0, column = 0;
  auto digits = [&](std::size_t& out) {
    const std::size_t s = i;
    while (i < e.size() && e[i] >= '0' && e[i] <= '9') out = out * 10 + static_cast<std::size_t>(e[i++] - '0');
    return i > s && i - s < 10;
  };
  if (!digits(line) || i >= e.size() || e[i++] != ':') return false;
  if (!digits(column) || i + 1 >= e.size() || e[i] != ':' || e[i + 1] != ' ') return false;
  std::size_t lines = 1;
  for (char c : text) lines += c == '\n';
  return line >= 1 && line <= lines && column >= 1;
}

TEST(GenomeText, RealRoundTripAndFields) {
  const Genome g = must_parse(real_text());
  ASSERT_EQ(kind_of(g), GenomeKind::kReal);
  const RealGenome& r = std::get<RealGenome>(g);
  EXPECT_EQ(r.values.size(), 16u);
  EXPECT_EQ(r.values[1], -0.25);
  EXPECT_EQ(r.values[10], -1e-310) << "subnormals read exactly";
  EXPECT_EQ(r.sigma, 0.5);
  EXPECT_EQ(r.sigma_min, 0.001);
  EXPECT_EQ(r.sigma_max, 4);
  expect_round_trip(g);

  // Defaults for bounds and sigma; keys in any order; an empty gene list.
  const Genome d = must_parse("genome real\nvalues 1\n");
  EXPECT_EQ(std::get<RealGenome>(d).lo, -4);
  EXPECT_EQ(std::get<RealGenome>(d).sigma, 1);
  const Genome o = must_parse("genome real\nvalues\n  1 2\nsigma 2 max 3 min 0.5\nbounds 0 10\n");
  EXPECT_EQ(std::get<RealGenome>(o).values, (std::vector<double>{1, 2}));
  EXPECT_EQ(std::get<RealGenome>(o).sigma_max, 3);
  expect_round_trip(o);
  expect_round_trip(must_parse("genome real\nvalues\n"));
}

TEST(GenomeText, AhhsAndLindaRoundTrip) {
  const Genome a = must_parse(ahhs_text());
  ASSERT_EQ(kind_of(a), GenomeKind::kAhhs);
  auto direct = control::ahhs::parse_network(read_shipped("ahhs/two_hormone.ahhs"));
  ASSERT_TRUE(direct.ok());
  EXPECT_TRUE(std::get<control::ahhs::Network>(a) == *direct) << "the embedded text is the controller's own";
  expect_round_trip(a);

  const Genome l = must_parse(linda_text());
  ASSERT_EQ(kind_of(l), GenomeKind::kLinda);
  auto linda = control::snn::parse_genome(read_shipped("linda/avoider.genome"));
  ASSERT_TRUE(linda.ok());
  EXPECT_TRUE(std::get<control::snn::Genome>(l) == *linda);
  expect_round_trip(l);
}

TEST(GenomeText, TwoHundredMutantsOfEachKindRoundTrip) {
  kernel::RandomStream random(11);
  const std::vector<Genome> seeds = {Genome{random_real_genome(18, random)}, must_parse(ahhs_text()),
                                     must_parse(linda_text())};
  for (const Genome& seed : seeds) {
    Genome g = seed;
    std::size_t changed = 0;
    for (int i = 0; i < 200; ++i) {
      const Genome before = g;
      mutate(g, random);
      changed += !(g == before);
      ASSERT_NO_FATAL_FAILURE(expect_round_trip(g)) << kind_name(kind_of(g)) << " mutant " << i;
    }
    EXPECT_GT(changed, 150u) << kind_name(kind_of(seed)) << ": mutation should change most genomes";
  }
}

struct Malformed {
  std::string text;
  std::string error;  // the whole message
};

TEST(GenomeText, MalformedTextsHaveExactLocations) {
  const std::vector<Malformed> cases = {
      // The header.
      {"", "1:1: empty text: expected 'genome real|ahhs|linda'"},
      {"# only a comment\n", "2:1: empty text: expected 'genome real|ahhs|linda'"},
      {"values 1 2\n", "1:1: expected 'genome real|ahhs|linda' first, not 'values'"},
      {"genome\n", "1:7: 'genome' needs a kind: real, ahhs or linda"},
      {"  genome neat\n", "1:10: unknown genome kind 'neat' (real, ahhs or linda)"},
      {"genome real extra\nvalues 1\n", "1:13: nothing may follow 'genome real' on its line"},
      {"genome linda extra\n", "1:14: nothing may follow 'genome linda' on its line"},
      {"\xff", "1:1: unexpected character (code 255)"},
      {"genome real\ngenome real\n", "2:1: 'genome' given twice (first at line 1)"},
      // Real: keys.
      {"genome real\n", "2:1: missing 'values' (the genes)"},
      {"genome real\nbounds -4 4", "2:12: missing 'values' (the genes)"},
      {"genome real\nvalues 1\nvalues 2\n", "3:1: 'values' given twice (first at line 2)"},
      {"genome real\nvalues 1\nweights 2\n", "3:1: unknown key 'weights' (bounds, sigma or values)"},
      {"genome real\n3 4\nvalues 1\n", "2:1: number '3' outside a list: a line starts with bounds, sigma or values"},
      {"genome real\nvalues 1\nbounds -4 4\n 5\n",
       "4:2: number '5' outside a list: a line starts with bounds, sigma or values"},
      {"genome real\nvalues 1 \x01\n", "2:10: unexpected character (code 1)"},
      // Real: bounds.
      {"genome real\nbounds -4\nvalues 1\n", "2:10: bounds needs two numbers: lo hi"},
      {"genome real\nbounds -4 4 5\nvalues 1\n", "2:13: bounds takes two numbers: lo hi"},
      {"genome real\nbounds 4 -4\nvalues 1\n", "2:10: bounds: lo 4 must be below hi -4"},
      {"genome real\nbounds 2 2\nvalues 2\n", "2:10: bounds: lo 2 must be below hi 2"},
      {"genome real\nbounds -4 x\nvalues 1\n", "2:11: 'x' is not a number"},
      {"genome real\nbounds -inf 4\nvalues 1\n", "2:8: number '-inf' is not finite"},
      {"genome real\nbounds -4 4\nbounds -4 4\nvalues 1\n", "3:1: 'bounds' given twice (first at line 2)"},
      // Real: sigma.
      {"genome real\nsigma\nvalues 1\n", "2:6: sigma needs a value"},
      {"genome real\nsigma 1 min\nvalues 1\n", "2:12: 'min' needs a number"},
      {"genome real\nsigma 1 step 2\nvalues 1\n", "2:9: sigma takes 'min A' and 'max B' after its value, not 'step'"},
      {"genome real\nsigma 1 min 0.1 min 0.2\nvalues 1\n", "2:17: 'min' given twice"},
      {"genome real\nsigma 0 min 0\nvalues 1\n", "2:13: sigma min 0 must be above 0"},
      {"genome real\nsigma 1 min 0.5 max 0.25\nvalues 1\n", "2:21: sigma max 0.25 below min 0.5"},
      {"genome real\nsigma 5\nvalues 1\n", "2:7: sigma 5 outside [1e-04, 4] (its min and max)"},
      {"  genome real # c\n  values 1 # two\n  sigma 9", "3:9: sigma 9 outside [1e-04, 4] (its min and max)"},
      {"genome real\nvalues 1\nsigma 1\nsigma 2\n", "4:1: 'sigma' given twice (first at line 3)"},
      // Real: values.
      {"genome real\nvalues 1 2 x\n", "2:12: 'x' is not a number"},
      {"genome real\nvalues 1 nan\n", "2:10: number 'nan' is not finite"},
      {"genome real\nvalues 1 inf\n", "2:10: number 'inf' is not finite"},
      {"genome real\nvalues 1e999\n", "2:8: number '1e999' out of range"},
      {"genome real\nvalues 1 2.5.3\n", "2:10: '2.5.3' is not a number"},
      {"genome real\nvalues --1\n", "2:8: '--1' is not a number"},
      {"genome real\nvalues +\n", "2:8: '+' is not a number"},
      {"genome real\nvalues 0x10\n", "2:8: '0x10' is not a number"},
      {"genome real\nvalues 1 2\n  3 4.5\n", "3:5: value 3: 4.5 outside bounds [-4, 4]"},
      {"genome real\nvalues 1\nbounds 0 0.5\n", "2:8: value 0: 1 outside bounds [0, 0.5]"},
      // Embedded AHHS: that parser's message, the line moved to the whole file.
      {"genome ahhs\n", "2:1: empty description: declare compartments, hormones and rules"},
      {"genome ahhs", "1:12: empty description: declare compartments, hormones and rules"},
      {"# x\n\ngenome ahhs\ncompartments x\n", "4:14: the number of compartments must be a whole number, got 'x'"},
      {"genome ahhs\ncompartments 2\nlink 0 5\n", "3:8: a compartment must be at most 1"},
      {"# a\n# b\ngenome ahhs   # comment\ncompartments 1\nhormone a base 0 decay 0 diffusion 0\n"
       "rule hormone a -> b centre 0 width 1 fixed 0\n",
       "6:19: no hormone named 'b' declared above"},
      {"genome ahhs\ncompartments 1\n\xc3\xa9\n", "3:1: unexpected character (code 195)"},
      // Embedded Linda.
      {"genome linda\ngrid 1 1\n", "3:1: missing a seed cell ('seed at X Y class C')"},
      {"genome linda\ngrid 1 1\nseed at 3 0 class RS\n", "3:9: x 3 outside the grid (0..0)"},
      {"# a genome\ngenome linda\ngrid 2 2\nseed at 0 0 class XX\n",
       "4:19: unknown neuron class 'XX' (RS, IB, CH, FS, LTS, TC or RZ)"},
  };
  EXPECT_GE(cases.size(), 40u);
  for (const Malformed& c : cases) {
    auto r = parse_genome_text(c.text);
    ASSERT_FALSE(r.ok()) << "accepted:\n" << c.text;
    EXPECT_EQ(r.error(), c.error) << "text:\n" << c.text;
  }
}

// Splits text into tokens and the whitespace between them, so a mutant keeps the rest intact.
std::vector<std::string> pieces(const std::string& text) {
  std::vector<std::string> out;
  std::size_t i = 0;
  while (i < text.size()) {
    const bool space = text[i] == ' ' || text[i] == '\n';
    std::size_t j = i;
    while (j < text.size() && (text[j] == ' ' || text[j] == '\n') == space) ++j;
    out.push_back(text.substr(i, j - i));
    i = j;
  }
  return out;
}

TEST(GenomeText, ThousandTokenMutantsAreLocatedErrorsOrValidGenomes) {
  const std::vector<std::string> seeds = {real_text(), ahhs_text(), linda_text(),
                                          "genome real\nbounds -1 1\nsigma 0.1\nvalues 0 0.5 -0.5 1\n"};
  const std::vector<std::string> pool = {
      "genome", "real",         "ahhs", "linda",   "bounds", "sigma", "min",  "max",  "values",
      "0",      "-4",           "4",    "1e999",   "nan",    "-inf",  "#",    "\n",   "x",
      "1e-320", "compartments", "rule", "hormone", "->",     "grid",  "seed", "gene", "99999999999999999999",
      ";",      "\t",           "-",    "+1"};
  kernel::RandomStream random(12);
  std::size_t valid = 0, errors = 0;
  for (int n = 0; n < 1000; ++n) {
    std::vector<std::string> p = pieces(seeds[random.below(seeds.size())]);
    const int edits = 1 + static_cast<int>(random.below(3));
    for (int e = 0; e < edits && !p.empty(); ++e) {
      const std::size_t i = random.below(p.size());
      switch (random.below(5)) {
        case 0: p.erase(p.begin() + static_cast<std::ptrdiff_t>(i)); break;
        case 1: p.insert(p.begin() + static_cast<std::ptrdiff_t>(i), p[i]); break;
        case 2: p[i] = pool[random.below(pool.size())]; break;
        case 3: std::swap(p[i], p[random.below(p.size())]); break;
        default:
          p.insert(p.begin() + static_cast<std::ptrdiff_t>(i), " " + pool[random.below(pool.size())] + " ");
          break;
      }
    }
    std::string text;
    for (const std::string& s : p) text += s;
    auto r = parse_genome_text(text);
    if (!r) {
      ++errors;
      ASSERT_TRUE(located_within(r.error(), text)) << r.error() << "\n" << text;
      continue;
    }
    ++valid;
    ASSERT_NO_FATAL_FAILURE(expect_round_trip(*r)) << text;
  }
  RecordProperty("valid", static_cast<int>(valid));
  RecordProperty("errors", static_cast<int>(errors));
  // Both outcomes occur: the mutants exercise the parser, not only its first check.
  EXPECT_GT(valid, 50u);
  EXPECT_GT(errors, 300u);
}

TEST(GenomeDiff, RealFields) {
  Genome a = must_parse(real_text());
  EXPECT_TRUE(diff(a, a).empty());
  Genome b = a;
  RealGenome& r = std::get<RealGenome>(b);
  r.values[3] = 0.75;
  r.sigma = 0.25;
  EXPECT_EQ(diff(a, b), (std::vector<std::string>{"sigma: 0.5 -> 0.25", "value 3: 2 -> 0.75"}));
  r = std::get<RealGenome>(a);
  r.lo = -8;
  r.sigma_max = 2;
  r.values.pop_back();
  EXPECT_EQ(diff(a, b),
            (std::vector<std::string>{"bounds: [-4, 4] -> [-8, 4]", "sigma max: 4 -> 2", "length: 16 -> 15"}));
  EXPECT_EQ(diff(a, Genome{must_parse(ahhs_text())}), (std::vector<std::string>{"kind: real -> ahhs"}));
}

TEST(GenomeDiff, LongListsAreCut) {
  RealGenome a;
  a.values.assign(100, 0.0);
  RealGenome b = a;
  for (double& v : b.values) v = 1;
  const auto d = diff(Genome{a}, Genome{b});
  ASSERT_EQ(d.size(), 31u);
  EXPECT_EQ(d[0], "value 0: 0 -> 1");
  EXPECT_EQ(d.back(), "... and 70 more");
}

// The line of `text` (1-based) that starts with `prefix`.
std::size_t line_of(const std::string& text, const std::string& prefix) {
  std::size_t line = 1, start = 0;
  while (start < text.size()) {
    if (text.compare(start, prefix.size(), prefix) == 0) return line;
    start = text.find('\n', start);
    if (start == std::string::npos) break;
    ++start;
    ++line;
  }
  return 0;
}

TEST(GenomeDiff, EmbeddedTextsDiffByLine) {
  const Genome a = must_parse(ahhs_text());
  Genome b = a;
  auto& net = std::get<control::ahhs::Network>(b);
  net.rules[2].fixed = 0.5f;
  const std::string text_a = to_text(a), text_b = to_text(b);
  const auto d = diff(a, b);
  ASSERT_EQ(d.size(), 2u) << ::testing::PrintToString(d);
  const std::size_t line = line_of(text_b, "rule sensor 2 ");
  ASSERT_GT(line, 0u) << text_b;
  EXPECT_EQ(d[0].rfind("line " + std::to_string(line) + ": - rule sensor 2 -> obstacle", 0), 0u) << d[0];
  EXPECT_NE(d[0].find("fixed 1"), std::string::npos) << d[0];
  EXPECT_EQ(d[1].rfind("line " + std::to_string(line) + ": + rule sensor 2 -> obstacle", 0), 0u) << d[1];
  EXPECT_NE(d[1].find("fixed 0.5"), std::string::npos) << d[1];

  // A Linda gene removed: one line gone, nothing added.
  const Genome l = must_parse(linda_text());
  Genome m = l;
  auto& genes = std::get<control::snn::Genome>(m).genes;
  genes.erase(genes.begin() + 1);
  const auto dl = diff(l, m);
  ASSERT_EQ(dl.size(), 1u) << ::testing::PrintToString(dl);
  EXPECT_NE(dl[0].find(": - gene once class TC when 1 do divide south CH"), std::string::npos) << dl[0];
}

TEST(GenomeOperators, MutationDispatchesAndStaysValid) {
  kernel::RandomStream random(13);
  Genome real = Genome{random_real_genome(16, random)};
  const Genome before = real;
  mutate(real, random);
  const auto& r = std::get<RealGenome>(real);
  EXPECT_NE(r.sigma, 1.0) << "log-normal self-adaptation changed sigma";
  for (std::size_t i = 0; i < r.values.size(); ++i) EXPECT_NE(r.values[i], std::get<RealGenome>(before).values[i]);
  EXPECT_TRUE(check(real).ok());

  kernel::RandomStream r1(5), r2(5);
  Genome x = must_parse(linda_text()), y = x;
  mutate(x, r1);
  mutate(y, r2);
  EXPECT_TRUE(x == y) << "same stream, same mutant";
}

TEST(GenomeOperators, CrossoverPerKind) {
  kernel::RandomStream random(14);
  // Different kinds: a copy of a.
  const Genome real_a = Genome{random_real_genome(16, random)};
  const Genome ahhs_a = must_parse(ahhs_text());
  EXPECT_TRUE(crossover(real_a, ahhs_a, random) == real_a);

  // Real: uniform.
  const Genome real_b = Genome{random_real_genome(16, random)};
  const Genome rc = crossover(real_a, real_b, random);
  for (std::size_t i = 0; i < 16; ++i) {
    const double v = std::get<RealGenome>(rc).values[i];
    EXPECT_TRUE(v == std::get<RealGenome>(real_a).values[i] || v == std::get<RealGenome>(real_b).values[i]);
  }

  // AHHS with the same structure: every number from one parent or the other, both parents used.
  Genome ahhs_b = ahhs_a;
  control::ahhs::MutationOptions strong;
  strong.hormone_probability = 1;
  strong.rule_probability = 1;
  strong.step = 0.3;
  GenomeMutation options;
  options.ahhs = strong;
  for (int i = 0; i < 5; ++i) mutate(ahhs_b, random, options);
  const auto& na = std::get<control::ahhs::Network>(ahhs_a);
  const auto& nb = std::get<control::ahhs::Network>(ahhs_b);
  ASSERT_TRUE(same_structure(na, nb));
  std::size_t from_a = 0, from_b = 0;
  for (int k = 0; k < 50; ++k) {
    const Genome c = crossover(ahhs_a, ahhs_b, random);
    ASSERT_TRUE(check(c).ok());
    const auto& nc = std::get<control::ahhs::Network>(c);
    ASSERT_TRUE(same_structure(na, nc));
    for (std::size_t i = 0; i < nc.rules.size(); ++i) {
      const float f = nc.rules[i].fixed;
      ASSERT_TRUE(f == na.rules[i].fixed || f == nb.rules[i].fixed);
      if (na.rules[i].fixed != nb.rules[i].fixed) (f == na.rules[i].fixed ? from_a : from_b)++;
    }
    for (std::size_t i = 0; i < nc.hormones.size(); ++i)
      ASSERT_TRUE(nc.hormones[i].decay == na.hormones[i].decay || nc.hormones[i].decay == nb.hormones[i].decay);
  }
  EXPECT_GT(from_a, 100u);
  EXPECT_GT(from_b, 100u);

  // AHHS with a different structure: a copy of a.
  Genome other = ahhs_a;
  std::get<control::ahhs::Network>(other).rules.pop_back();
  EXPECT_FALSE(same_structure(na, std::get<control::ahhs::Network>(other)));
  EXPECT_TRUE(crossover(ahhs_a, other, random) == ahhs_a);

  // Linda: the genome's own crossover, valid.
  const Genome la = must_parse(linda_text());
  Genome lb = la;
  for (int i = 0; i < 10; ++i) mutate(lb, random);
  for (int k = 0; k < 20; ++k) EXPECT_TRUE(check(crossover(la, lb, random)).ok());
}

}  // namespace
}  // namespace symb::evo
