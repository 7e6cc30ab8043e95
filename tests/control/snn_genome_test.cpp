// The Linda genome's text form: a full example parses to the expected genome; malformed texts are
// rejected with the LINE:COLUMN of the offending token; random token edits of a valid text are
// either rejected with a located error or give a genome that passes check_genome; to_text round
// trips bit for bit (the example, mutated genomes); mutation and crossover keep genomes valid.
#include <cctype>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "symb/control/snn/genome.hpp"
#include "symb/control/snn/genome_mutation.hpp"
#include "symb/kernel/random_stream.hpp"

namespace symb::control::snn {
namespace {

const char* const kExample = R"(# every statement and action once
grid 10 8
ticks 30
warmup 5
noise 0.25
integration euler
reach 2
morphogen light diffusion 0.2 decay 0.1
morphogen dark diffusion 0 decay 1
source light at 9 7 rate 2.5
seed at 1 1 class RS
seed at 2 1 class FS bias -3.5
input 0 at 0 0
input 3 at 9 0
output 1 at 5 7
gene when 1 do secrete dark 0.5
gene once class FS when -0.5 2*light -1e-3*dark do move up light
gene when 0 do move west
gene when 0.1 do divide down dark CH
gene when 0.1 do divide south IB
gene class CH when -1 3*dark do die
gene once when 1 do grow up light weight 12.5 delay 3
gene when 1 do grow down dark weight -7 delay 0
gene when 1 do prune
gene when 1 do weight -0.125
gene when 1 do bias 4
gene when 1 do class LTS
)";

bool located(const std::string& e) {
  std::size_t i = 0;
  auto digits = [&] {
    const std::size_t s = i;
    while (i < e.size() && std::isdigit(static_cast<unsigned char>(e[i]))) ++i;
    return i > s;
  };
  if (!digits() || i >= e.size() || e[i++] != ':') return false;
  if (!digits() || i + 1 >= e.size()) return false;
  return e[i] == ':' && e[i + 1] == ' ';
}

TEST(LindaGenomeParser, FullExampleGivesTheExpectedGenome) {
  auto r = parse_genome(kExample);
  ASSERT_TRUE(r.ok()) << r.error();
  const Genome& g = *r;
  EXPECT_EQ(g.width, 10);
  EXPECT_EQ(g.height, 8);
  EXPECT_EQ(g.ticks, 30);
  EXPECT_EQ(g.warmup, 5);
  EXPECT_EQ(g.noise, 0.25f);
  EXPECT_EQ(g.integration, Integration::kEuler);
  EXPECT_EQ(g.reach, 2.0f);
  ASSERT_EQ(g.morphogens.size(), 2u);
  EXPECT_EQ(g.morphogens[0], (Morphogen{"light", 0.2f, 0.1f}));
  EXPECT_EQ(g.morphogens[1], (Morphogen{"dark", 0.0f, 1.0f}));
  ASSERT_EQ(g.sources.size(), 1u);
  EXPECT_EQ(g.sources[0], (Source{0, 9, 7, 2.5f}));
  ASSERT_EQ(g.seeds.size(), 2u);
  EXPECT_EQ(g.seeds[0], (SeedCell{1, 1, NeuronClass::kRS, 0.0f}));
  EXPECT_EQ(g.seeds[1], (SeedCell{2, 1, NeuronClass::kFS, -3.5f}));
  EXPECT_EQ(g.inputs, (std::vector<ChannelSite>{{0, 0, 0}, {3, 9, 0}}));
  EXPECT_EQ(g.outputs, (std::vector<ChannelSite>{{1, 5, 7}}));
  ASSERT_EQ(g.genes.size(), 12u);

  Gene secrete;
  secrete.bias = 1;
  secrete.action = ActionKind::kSecrete;
  secrete.morphogen = 1;
  secrete.amount = 0.5f;
  EXPECT_EQ(g.genes[0], secrete);

  Gene move_up;
  move_up.once = true;
  move_up.only = NeuronClass::kFS;
  move_up.bias = -0.5f;
  move_up.terms = {{0, 2.0f}, {1, -1e-3f}};
  move_up.action = ActionKind::kMove;
  move_up.direction = Direction::kUp;
  move_up.morphogen = 0;
  EXPECT_EQ(g.genes[1], move_up);

  EXPECT_EQ(g.genes[2].action, ActionKind::kMove);
  EXPECT_EQ(g.genes[2].direction, Direction::kWest);
  EXPECT_EQ(g.genes[2].morphogen, -1);

  EXPECT_EQ(g.genes[3].action, ActionKind::kDivide);
  EXPECT_EQ(g.genes[3].direction, Direction::kDown);
  EXPECT_EQ(g.genes[3].morphogen, 1);
  EXPECT_EQ(g.genes[3].cls, NeuronClass::kCH);
  EXPECT_EQ(g.genes[4].direction, Direction::kSouth);
  EXPECT_EQ(g.genes[4].cls, NeuronClass::kIB);

  EXPECT_EQ(g.genes[5].action, ActionKind::kDie);
  EXPECT_EQ(g.genes[5].only, NeuronClass::kCH);
  EXPECT_EQ(g.genes[5].terms, (std::vector<Term>{{1, 3.0f}}));

  Gene grow;
  grow.once = true;
  grow.bias = 1;
  grow.action = ActionKind::kGrow;
  grow.direction = Direction::kUp;
  grow.morphogen = 0;
  grow.amount = 12.5f;
  grow.delay = 3;
  EXPECT_EQ(g.genes[6], grow);
  EXPECT_EQ(g.genes[7].direction, Direction::kDown);
  EXPECT_EQ(g.genes[7].morphogen, 1);
  EXPECT_EQ(g.genes[7].amount, -7.0f);
  EXPECT_EQ(g.genes[7].delay, 0);

  EXPECT_EQ(g.genes[8].action, ActionKind::kPrune);
  EXPECT_EQ(g.genes[9].action, ActionKind::kWeight);
  EXPECT_EQ(g.genes[9].amount, -0.125f);
  EXPECT_EQ(g.genes[10].action, ActionKind::kBias);
  EXPECT_EQ(g.genes[10].amount, 4.0f);
  EXPECT_EQ(g.genes[11].action, ActionKind::kClass);
  EXPECT_EQ(g.genes[11].cls, NeuronClass::kLTS);
  EXPECT_TRUE(check_genome(g).ok());
}

TEST(LindaGenomeParser, DefaultsAndAnyStatementOrder) {
  auto g = parse_genome(
      "gene when 1 do die\n"
      "morphogen m diffusion 0.25 decay 0\n"
      "grid 3 2\n"
      "seed at 2 1 class RZ\n"
      "source m at 0 0 rate -1\n"
      "ticks 0\n");
  ASSERT_TRUE(g.ok()) << g.error();
  EXPECT_EQ(g->warmup, 0);
  EXPECT_EQ(g->noise, 0.0f);
  EXPECT_EQ(g->reach, 1.5f);
  EXPECT_EQ(g->integration, Integration::kPublished);
  EXPECT_EQ(g->ticks, 0);
  EXPECT_EQ(g->seeds[0].cls, NeuronClass::kRZ);
}

struct Bad {
  std::string text;
  std::string where;  // "LINE:COLUMN:"
};

TEST(LindaGenomeParser, MalformedInputsAreRejectedWithTheirLocation) {
  const std::string p = "grid 8 6\nmorphogen a diffusion 0.1 decay 0.05\nseed at 1 1 class RS\n";  // 3 lines
  std::string many_morphogens = "grid 8 6\nseed at 0 0 class RS\n";
  for (int i = 0; i < 17; ++i) many_morphogens += "morphogen m" + std::to_string(i) + " diffusion 0 decay 0\n";
  std::string many_genes = p;
  for (int i = 0; i < 257; ++i) many_genes += "gene when 1 do die\n";
  std::string many_terms = p + "gene when 1";
  for (int i = 0; i < 17; ++i) many_terms += " 1*a";  // the 17th term starts at column 13 + 16 * 4
  many_terms += " do die\n";
  std::string many_seeds = "grid 64 64\n";
  for (int i = 0; i < 257; ++i)
    many_seeds += "seed at " + std::to_string(i % 64) + " " + std::to_string(i / 64) + " class RS\n";
  const std::vector<Bad> cases = {
      {"grid 8 6\nfoo 1\n", "2:1:"},                                                  // unknown statement
      {"grid 8 x\nseed at 0 0 class RS\n", "1:8:"},                                   // bad number
      {"grid 65 6\n", "1:6:"},                                                        // out of range
      {"grid 0 6\n", "1:6:"},                                                         // out of range
      {"grid 8 6.5\n", "1:8:"},                                                       // not whole
      {p + "ticks 2001\n", "4:7:"},                                                   // out of range
      {p + "ticks -1\n", "4:7:"},                                                     // out of range
      {p + "warmup 99999999999999999999999\n", "4:8:"},                               // out of range
      {p + "morphogen b diffusion 0.3 decay 0\n", "4:23:"},                           // diffusion > 0.25
      {p + "morphogen b diffusion 0.1 decay 1.5\n", "4:33:"},                         // decay > 1
      {p + "morphogen b diffusion 0.1 rate 0.5\n", "4:27:"},                          // keyword
      {p + "source b at 1 1 rate 1\n", "4:8:"},                                       // undeclared morphogen
      {p + "morphogen a diffusion 0 decay 0\n", "4:11:"},                             // duplicate morphogen
      {p + "seed at 8 0 class RS\n", "4:9:"},                                         // site outside (x)
      {p + "source a at 0 6 rate 1\n", "4:15:"},                                      // site outside (y)
      {p + "seed at 1 1 class FS\n", "4:9:"},                                         // duplicate seed site
      {"morphogen a diffusion 0 decay 0\n", "2:1:"},                                  // missing grid
      {"", "1:1:"},                                                                   // missing grid
      {"grid 8 6\n# no seed", "2:10:"},                                               // missing seed
      {"seed at 1 1 class RS\ngrid 8 6\n", "1:9:"},                                   // site before grid
      {p + "gene do die\n", "4:6:"},                                                  // no `when`
      {p + "gene when 1 1*a\n", "4:16:"},                                             // no `do`
      {p + "gene when 1 do fly\n", "4:16:"},                                          // unknown action
      {p + "gene when 1 do secrete a\n", "4:25:"},                                    // missing argument
      {p + "gene when 1 do\n", "4:15:"},                                              // missing action
      {p + "gene when 1 do die now\n", "4:20:"},                                      // trailing token
      {"grid 8 6 7\n", "1:10:"},                                                      // trailing token
      {many_morphogens, "19:1:"},                                                     // too many morphogens
      {many_genes, "260:1:"},                                                         // too many genes
      {many_terms, "4:77:"},                                                          // too many terms
      {many_seeds, "258:1:"},                                                         // too many seeds
      {p + "# " + std::string(1100, 'x') + "\n", "4:1025:"},                          // over-long line
      {p + "morphogen " + std::string(33, 'n') + " diffusion 0 decay 0\n", "4:11:"},  // over-long name
      {p + "morphogen 1a diffusion 0 decay 0\n", "4:11:"},                            // bad name
      {p + "gene when 1 2*b do die\n", "4:15:"},                                      // undeclared in a term
      {p + "gene when 1 x*a do die\n", "4:13:"},                                      // bad term weight
      {p + "gene when 1 1 do die\n", "4:13:"},                                        // not a term
      {p + "noise nan\n", "4:7:"},                                                    // nan
      {p + "gene when inf do die\n", "4:11:"},                                        // inf
      {p + "gene when 1e5 do die\n", "4:11:"},                                        // |number| > 1e4
      {p + "gene when 1 do bias 1001\n", "4:21:"},                                    // bias limit
      {p + "seed at 2 2 class XX\n", "4:19:"},                                        // unknown class
      {p + "gene class Q when 1 do die\n", "4:12:"},                                  // unknown class
      {p + "gene when 1 do move nowhere\n", "4:21:"},                                 // unknown direction
      {p + "gene when 1 do move up\n", "4:23:"},                                      // missing gradient
      {p + "gene when 1 do divide east\n", "4:27:"},                                  // missing class
      {p + "gene when 1 do grow north a weight 1 delay 1\n", "4:21:"},                // grow is up/down
      {p + "gene when 1 do grow up a weight 1 delay 64\n", "4:41:"},                  // delay > 63
      {p + "gene when 1 do grow up a weight 101 delay 1\n", "4:33:"},                 // weight > 100
      {p + "gene when 1 do grow up a weight 1\n", "4:34:"},                           // missing delay
      {"grid 8 6\ngrid 8 6\n", "2:1:"},                                               // duplicate statement
      {p + "integration rk4\n", "4:13:"},                                             // unknown integration
      {p + "input 32 at 0 0\n", "4:7:"},                                              // channel out of range
      {p + "output 1 at 0\n", "4:14:"},                                               // missing y
      {p + "seed at 2 2 class RS bias\n", "4:26:"},                                   // missing bias value
      {p + "seed at 2 2 class RS bias 1001\n", "4:27:"},                              // bias out of range
      {std::string("grid 8 6\x01\n"), "1:9:"},                                        // control character
      {p + "reach -1\n", "4:7:"},                                                     // negative reach
  };
  ASSERT_GE(cases.size(), 30u);
  for (const auto& c : cases) {
    auto r = parse_genome(c.text);
    ASSERT_FALSE(r.ok()) << "accepted:\n" << c.text.substr(0, 300);
    EXPECT_EQ(r.error().substr(0, c.where.size()), c.where) << r.error() << "\nfor:\n" << c.text.substr(0, 300);
    EXPECT_TRUE(located(r.error())) << r.error();
  }
}

// The example's tokens with their offsets, for token edits.
std::vector<std::pair<std::size_t, std::size_t>> token_spans(const std::string& text) {
  std::vector<std::pair<std::size_t, std::size_t>> out;
  std::size_t i = 0;
  while (i < text.size()) {
    if (std::isspace(static_cast<unsigned char>(text[i]))) {
      ++i;
      continue;
    }
    const std::size_t s = i;
    while (i < text.size() && !std::isspace(static_cast<unsigned char>(text[i]))) ++i;
    out.emplace_back(s, i - s);
  }
  return out;
}

TEST(LindaGenomeParser, TokenEditsAreRejectedWithALocationOrGiveAValidGenome) {
  const std::string base = kExample;
  const auto tokens = token_spans(base);
  const std::vector<std::string> junk = {"-1",   "1e9", "nan", "zz",   "*",  "class", "99", "0", "light", "do",
                                         "when", "up",  "-0",  "1*zz", "64", "FS",    "\t", "#", "gene",  "2.5e-3"};
  kernel::RandomStream random(42);
  int accepted = 0, rejected = 0;
  for (int trial = 0; trial < 500; ++trial) {
    std::string text = base;
    const int edits = 1 + static_cast<int>(random.below(3));
    for (int e = 0; e < edits; ++e) {
      const auto [at, len] = tokens[random.below(tokens.size())];
      if (at + len > text.size()) continue;
      switch (random.below(4)) {
        case 0: text.erase(at, len); break;
        case 1: text.insert(at, text.substr(at, len) + " "); break;
        case 2: {
          const std::string with = random.below(2) ? junk[random.below(junk.size())]
                                                   : base.substr(tokens[random.below(tokens.size())].first,
                                                                 tokens[random.below(tokens.size())].second);
          text.replace(at, len, with);
          break;
        }
        default: text.resize(random.below(text.size() + 1)); break;
      }
    }
    auto r = parse_genome(text);
    if (!r.ok()) {
      ++rejected;
      EXPECT_TRUE(located(r.error())) << r.error();
    } else {
      ++accepted;
      EXPECT_TRUE(check_genome(*r).ok()) << check_genome(*r).error();
      auto again = parse_genome(to_text(*r));
      ASSERT_TRUE(again.ok()) << again.error();
      EXPECT_EQ(*again, *r);
    }
  }
  EXPECT_GT(accepted, 10);
  EXPECT_GT(rejected, 100);
}

TEST(LindaGenomeParser, ToTextRoundTripsTheExample) {
  auto g = parse_genome(kExample);
  ASSERT_TRUE(g.ok()) << g.error();
  const std::string text = to_text(*g);
  auto again = parse_genome(text);
  ASSERT_TRUE(again.ok()) << again.error() << "\n" << text;
  EXPECT_EQ(*again, *g);
  EXPECT_EQ(to_text(*again), text);
}

TEST(LindaGenomeParser, ToTextRoundTripsMutatedGenomesBitForBit) {
  auto g = parse_genome(kExample);
  ASSERT_TRUE(g.ok()) << g.error();
  kernel::RandomStream random(7);
  GenomeMutation strong;
  strong.number_rate = 0.5;
  strong.site_rate = 0.3;
  strong.gene_duplicate = 0.1;
  strong.gene_delete = 0.1;
  strong.term_add = 0.2;
  strong.term_delete = 0.1;
  strong.action_change = 0.2;
  Genome current = *g;
  for (int i = 0; i < 200; ++i) {
    mutate(current, random, strong);
    ASSERT_TRUE(check_genome(current).ok()) << check_genome(current).error() << "\n" << to_text(current);
    auto again = parse_genome(to_text(current));
    ASSERT_TRUE(again.ok()) << again.error() << "\n" << to_text(current);
    ASSERT_EQ(*again, current) << to_text(current);
    // Bit for bit, not just ==: -0 and 0 compare equal but print differently.
    EXPECT_EQ(to_text(*again), to_text(current));
  }
}

TEST(LindaGenomeParser, CheckGenomeNamesTheItem) {
  auto g = parse_genome(kExample);
  ASSERT_TRUE(g.ok());
  Genome bad = *g;
  bad.seeds[1].x = bad.seeds[0].x;
  bad.seeds[1].y = bad.seeds[0].y;
  EXPECT_NE(check_genome(bad).error().find("seed 1"), std::string::npos) << check_genome(bad).error();
  bad = *g;
  bad.genes[2].morphogen = 0;  // move west uses no morphogen: the text could not say it
  EXPECT_NE(check_genome(bad).error().find("gene 2"), std::string::npos) << check_genome(bad).error();
  bad = *g;
  bad.sources[0].x = 10;
  EXPECT_NE(check_genome(bad).error().find("source 0"), std::string::npos) << check_genome(bad).error();
  bad = *g;
  bad.genes[6].amount = 1e3f;  // grown weights stay within kMaxGrownWeight
  EXPECT_FALSE(check_genome(bad).ok());
}

TEST(LindaGenomeMutation, SameSeedSameMutantAndMovedSeedsStayDistinct) {
  auto g = parse_genome(kExample);
  ASSERT_TRUE(g.ok());
  Genome a = *g, b = *g;
  kernel::RandomStream ra(3), rb(3);
  for (int i = 0; i < 20; ++i) {
    mutate(a, ra);
    mutate(b, rb);
  }
  EXPECT_EQ(a, b);
  EXPECT_NE(a, *g);

  // Two seeds side by side on a 2x1 grid: a step onto the other's site never happens.
  auto tight = parse_genome("grid 2 1\nseed at 0 0 class RS\nseed at 1 0 class FS\ngene when 1 do die\n");
  ASSERT_TRUE(tight.ok()) << tight.error();
  GenomeMutation sites;
  sites.site_rate = 1.0;
  sites.number_rate = 0;
  kernel::RandomStream r(5);
  Genome t = *tight;
  for (int i = 0; i < 50; ++i) {
    mutate(t, r, sites);
    ASSERT_TRUE(check_genome(t).ok()) << check_genome(t).error();
  }
  EXPECT_EQ(t.seeds, tight->seeds);
  // Gene deletion never removes the last gene.
  GenomeMutation wipe;
  wipe.gene_delete = 1.0;
  mutate(t, r, wipe);
  EXPECT_EQ(t.genes.size(), 1u);
}

TEST(LindaGenomeMutation, CrossoverResultsAreValid) {
  auto g = parse_genome(kExample);
  ASSERT_TRUE(g.ok());
  auto other = parse_genome(
      "grid 4 4\nmorphogen dark diffusion 0 decay 0\nmorphogen smell diffusion 0.1 decay 0.1\n"
      "seed at 0 0 class RS\n"
      "gene when 1 do secrete smell 1\n"                       // names a morphogen the example lacks: dropped
      "gene when 1 1*dark do grow up dark weight 1 delay 1\n"  // dark is morphogen 1 in the example
      "gene when 1 do die\n");
  ASSERT_TRUE(other.ok()) << other.error();
  kernel::RandomStream random(11);
  bool saw_b_gene = false;
  for (int i = 0; i < 200; ++i) {
    Genome a = *g;
    Genome b = *other;
    GenomeMutation m;
    m.action_change = 0.2;
    mutate(a, random, m);
    const Genome child = crossover(a, b, random);
    ASSERT_TRUE(check_genome(child).ok()) << check_genome(child).error();
    EXPECT_EQ(child.morphogens, a.morphogens);
    EXPECT_EQ(child.seeds, a.seeds);
    for (const auto& gene : child.genes) {
      if (gene.action == ActionKind::kGrow && gene.terms == std::vector<Term>{{1, 1.0f}}) {
        saw_b_gene = true;
        EXPECT_EQ(gene.morphogen, 1);  // renumbered by name
      }
      if (gene.action == ActionKind::kSecrete) {
        EXPECT_NE(gene.amount, 1.0f);  // b's secrete smell never comes
      }
    }
    const Genome swapped = crossover(b, a, random);
    ASSERT_TRUE(check_genome(swapped).ok()) << check_genome(swapped).error();
  }
  EXPECT_TRUE(saw_b_gene);
}

}  // namespace
}  // namespace symb::control::snn
