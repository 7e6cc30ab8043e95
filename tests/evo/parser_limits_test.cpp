// The longest and deepest inputs each line-based parser can be handed: the AHHS description, the
// network description, the Linda genome, the real genome and the task-graph genome. None of them
// recurses (their grammars are flat: one statement a line), so a long input is read in a loop to
// the first limit it breaks and rejected there with its line and column, or accepted; all of it on
// a thread with 256 KiB of stack, 1/32 of the executors' default. And the shared scaffold they
// report through (kernel/source_text.hpp).
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "symb/control/ahhs/parser.hpp"
#include "symb/control/network/description.hpp"
#include "symb/control/snn/genome.hpp"
#include "symb/evo/embryogenesis/task_graph_genome.hpp"
#include "symb/evo/genome/genome.hpp"
#include "symb/kernel/source_text.hpp"

#include "support/small_stack.hpp"

namespace symb::evo {
namespace {

std::string repeat(std::string_view piece, std::size_t times) {
  std::string s;
  s.reserve(piece.size() * times);
  for (std::size_t i = 0; i < times; ++i) s += piece;
  return s;
}

template <class R>
std::string outcome(const R& r) {
  return r.ok() ? std::string("<accepted>") : r.error();
}

TEST(ParserLimits, LongInputsAreReadInALoopToALocatedError) {
  std::vector<std::pair<std::string, std::string>> cases;  // {input outcome, what it must say}
  ASSERT_TRUE(test_support::run_on_small_stack([&] {
    // AHHS: a line of 500,000 words; a million empty ';' statements; more links than allowed.
    cases.emplace_back(outcome(control::ahhs::parse_network("compartments 2" + repeat(" 1", 500000))),
                       "1:16: unexpected '1'");
    cases.emplace_back(outcome(control::ahhs::parse_network(repeat(";", 1000000) + "\ncompartments 1\n")),
                       "3:1: declare at least one hormone");
    cases.emplace_back(outcome(control::ahhs::parse_network("compartments 2\n" + repeat("link 0 1\n", 20000))),
                       "3:1: this link is given twice");
    // Network: a weight list of 100,000 numbers, one a line.
    cases.emplace_back(
        outcome(control::network::parse_description("type mlp\ninputs 1\nlayers 1\nweights\n" + repeat("1\n", 100000))),
        "more than 20000 numbers");
    // Linda: a line past its length, and more genes than allowed.
    cases.emplace_back(outcome(control::snn::parse_genome("grid 4 4 " + repeat("x", 5000))),
                       "1:1025: line longer than 1024 characters");
    cases.emplace_back(outcome(control::snn::parse_genome("grid 4 4\n" + repeat("gene north 1*a\n", 100000))), "2:");
    // Real genome: one value more than the limit, one a line.
    cases.emplace_back(
        outcome(parse_genome_text("genome real\nvalues\n" + repeat("0\n", kMaxRealGenes + 1))),
        std::to_string(kMaxRealGenes + 3) + ":1: more than " + std::to_string(kMaxRealGenes) + " values");
    // Task graph: more tasks than allowed; a hook line of a hundred thousand arrows.
    cases.emplace_back(outcome(parse_task_graph(repeat("task a mlp\n", 1000))), "257:1: more than 256 tasks");
    cases.emplace_back(outcome(parse_task_graph("hook a" + repeat(" -> b", 100000))), "1:");
  }));
  ASSERT_EQ(cases.size(), 9u);
  for (const auto& [got, want] : cases) {
    EXPECT_TRUE(kernel::split_location(got).at.has_value()) << got.substr(0, 200);
    EXPECT_NE(got.find(want), std::string::npos) << "'" << want << "' not in: " << got.substr(0, 200);
  }
}

TEST(SourceText, WordsLocationsAndTheNestingBound) {
  auto words = kernel::split_words("  link 0;1 # x\x01", 7, ";");
  ASSERT_TRUE(words.ok()) << words.error();
  ASSERT_EQ(words->size(), 4u);
  EXPECT_EQ((*words)[0].text, "link");
  EXPECT_EQ((*words)[0].column, 3u);
  EXPECT_EQ((*words)[2].text, ";");
  EXPECT_EQ((*words)[3].error_after("x").message, "7:11: x");
  EXPECT_EQ(kernel::split_words("ok \x7f", 2).error(), "2:4: unexpected character (code 127)");

  const auto m = kernel::split_location("12:3: bad");
  ASSERT_TRUE(m.at.has_value());
  EXPECT_EQ(m.at->line, 12u);
  EXPECT_EQ(m.at->column, 3u);
  EXPECT_EQ(m.message, "bad");
  EXPECT_FALSE(kernel::split_location("12:3 bad").at.has_value());
  EXPECT_FALSE(kernel::split_location("column 3: bad").at.has_value());

  std::vector<std::size_t> lines;
  ASSERT_TRUE(kernel::for_each_line("a\n\nb", [&](std::string_view, std::size_t n) -> kernel::Status {
    lines.push_back(n);
    return {};
  }));
  EXPECT_EQ(lines, (std::vector<std::size_t>{1, 2, 3}));

  kernel::NestingBound bound(2);
  int deepest = 0;
  const auto descend = [&](auto&& self) -> bool {
    const auto level = bound.enter();
    if (!level) return false;
    deepest = bound.depth();
    return self(self);
  };
  EXPECT_FALSE(descend(descend));
  EXPECT_EQ(deepest, 2);
  EXPECT_EQ(bound.depth(), 0);
}

}  // namespace
}  // namespace symb::evo
