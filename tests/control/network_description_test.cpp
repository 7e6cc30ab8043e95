// Network descriptions and weight lists: valid texts parse to the topology, scales and genome they
// say; every mistake is reported as "LINE:COLUMN: message" pointing at the offending text; 400
// seeded mutants of valid descriptions are each rejected with a located error or, when a mutation
// happens to leave a valid description, build a working network. The shipped weight file too.
#include <cmath>
#include <fstream>
#include <iostream>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "symb/control/network/description.hpp"

namespace symb::control::network {
namespace {

const char* kValidNetworks[] = {
    R"(# a Braitenberg perceptron
type mlp
inputs 7
layers 2
activation tanh
input_scale 0.000222
output_scale 500
weights
  1.5  2.0  2.5 -2.0 -1.5 0.5 0.5 0.6
 -1.5 -2.0 -2.5  2.0  1.5 0.5 0.5 0.6
)",
    R"(type elman
inputs 2
layers 2 1
activation sigmoid
input_scale 1 0.5
weights 0.1 0.2 0.3 0.4 0.5   0.6 0.7 0.8 0.9 1.0   1.1 1.2 1.3
)",
    R"(type ctrnn   # Beer 1995
inputs 1
layers 2 1
tau 0.1 0.2
weights
  1 0 0 0
  0 4 0 -2
)",
};

// "LINE:COLUMN: " at the start, both inside the text.
bool located_inside_network(const std::string& error, const std::string& text) {
  static const std::regex shape(R"(^(\d+):(\d+): .+)");
  std::smatch m;
  if (!std::regex_search(error, m, shape)) return false;
  const std::size_t line = std::stoul(m[1]), column = std::stoul(m[2]);
  std::vector<std::string> lines;
  std::stringstream ss(text);
  for (std::string l; std::getline(ss, l);) lines.push_back(l);
  if (lines.empty()) lines.emplace_back();
  return line >= 1 && line <= lines.size() && column >= 1 && column <= lines[line - 1].size() + 1;
}

TEST(NetworkDescription, ValidTextsParse) {
  auto a = parse_description(kValidNetworks[0]);
  ASSERT_TRUE(a.ok()) << a.error();
  EXPECT_EQ(a->topology.kind, Kind::kMlp);
  EXPECT_EQ(a->topology.inputs, 7u);
  EXPECT_EQ(a->topology.layers, std::vector<std::size_t>{2});
  ASSERT_TRUE(a->weights.has_value());
  EXPECT_EQ(a->weights->size(), 16u);
  EXPECT_FLOAT_EQ((*a->weights)[8], -1.5f);
  EXPECT_FLOAT_EQ(*a->output_scale, 500.0);
  EXPECT_EQ(a->input_scale, std::vector<float>{0.000222f});
  auto b = parse_description(kValidNetworks[1]);
  ASSERT_TRUE(b.ok()) << b.error();
  EXPECT_EQ(b->topology.kind, Kind::kElman);
  EXPECT_EQ(b->topology.activation, Activation::kSigmoid);
  EXPECT_EQ(b->input_scale.size(), 2u);
  auto c = parse_description(kValidNetworks[2]);
  ASSERT_TRUE(c.ok()) << c.error();
  EXPECT_EQ(c->topology.kind, Kind::kCtrnn);
  EXPECT_EQ(c->tau, (std::vector<float>{0.1f, 0.2f}));
  // No weights: the network starts at zero.
  auto d = parse_description("type mlp\nlayers 3 2\n");
  ASSERT_TRUE(d.ok()) << d.error();
  EXPECT_FALSE(d->weights.has_value());
}

TEST(NetworkDescription, MistakesAreLocated) {
  struct Case {
    std::string text;
    std::string error;  // the expected start of the message
  };
  const Case cases[] = {
      {"type mlp\nlayers 2\ninputs 7\nweights 1 2 x\n", "4:13: 'x' is not a number"},
      {"type mlp\nlayers 2\nbogus 3\n", "3:1: unknown key 'bogus'"},
      {"type mlp\nlayers 2\ntype elman\n", "3:1: 'type' given twice (first at line 1)"},
      {"type mlp\n  layers 0\n", "2:10: must be 1..64, got 0"},
      {"type perceptron\nlayers 2\n", "1:6: unknown network type 'perceptron'"},
      {"type mlp\nlayers 2\nactivation relu\n", "3:12: unknown activation 'relu'"},
      {"type mlp\nlayers 2\ninputs 2\nweights 1 2 3\n", "4:1: this network has 6 weights, got 3"},
      {"type mlp\nlayers 2\ninputs 3\ninput_scale 1 2\n", "4:1: input_scale takes one factor or one per input (3)"},
      {"type mlp\nlayers 2\ntau 0.1\n", "3:1: 'tau' is for ctrnn networks only"},
      {"type ctrnn\nlayers 2 1\ntau 0.1 -1\n", "3:9: time constants must be positive"},
      {"type ctrnn\nlayers 3\n", "2:8: a ctrnn takes layers \"N O\""},
      {"type elman\nlayers 4\n", "2:8: an elman network needs a hidden layer"},
      {"layers 2\n", "1:1: missing 'type'"},
      {"type mlp\n", "1:1: missing 'layers'"},
      {"type mlp mlp\nlayers 2\n", "1:10: 'type' takes one value"},
      {"type mlp\nlayers 2\noutput_scale -5\n", "3:14: output_scale must be positive"},
      {"type mlp\nlayers 2\nweights 1e99\n", "3:9: '1e99' is out of range"},
      {"type mlp\nlayers 2\nweights nan\n", "3:9: 'nan' is not a finite number"},
      {"type mlp\nlayers 2\ninputs 1.5\n", "3:8: '1.5' is not a whole number"},
      // A token nobody means is quoted cut at 24 bytes, so a bad line never floods the log.
      {"type mlp\nlayers 2\nbogus" + std::string(200, 'k') + " 1\n",
       "3:1: unknown key 'bogus" + std::string(19, 'k') + "...'"},
      {"", "1:1: missing 'type'"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.text);
    auto d = parse_description(c.text);
    ASSERT_FALSE(d.ok());
    EXPECT_EQ(d.error().rfind(c.error, 0), 0u) << d.error();
    EXPECT_TRUE(located_inside_network(d.error(), c.text)) << d.error();
  }
}

TEST(NetworkDescription, NumberListsAreLocated) {
  auto ok = parse_numbers("1 -2.5 +3 # a comment 4\n .5e1\n");
  ASSERT_TRUE(ok.ok()) << ok.error();
  EXPECT_EQ(*ok, (std::vector<float>{1.0f, -2.5f, 3.0f, 5.0f}));
  auto bad = parse_numbers("1 2\n 3 4x 5\n");
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error(), "2:4: '4x' is not a number");
  auto many = parse_numbers("1 2 3 4", 3);
  ASSERT_FALSE(many.ok());
  EXPECT_EQ(many.error(), "1:7: more than 3 numbers");
  auto inf = parse_numbers("inf");
  EXPECT_FALSE(inf.ok());
}

TEST(NetworkDescription, ShippedWeightFileIsTheBraitenbergPerceptron) {
  std::ifstream in(std::string(SYMB_SHIPPED_SCENARIO_DIR) + "/network/braitenberg.w");
  ASSERT_TRUE(in) << "scenarios/network/braitenberg.w";
  std::stringstream ss;
  ss << in.rdbuf();
  auto w = parse_numbers(ss.str());
  ASSERT_TRUE(w.ok()) << w.error();
  EXPECT_EQ(w->size(), genome_size({Kind::kMlp, 7, {2}, Activation::kTanh}));
}

std::vector<std::string> tokens_of(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  for (std::string t; ss >> t;) out.push_back(t);
  return out;
}

std::string mutate(const std::string& base, std::mt19937& rng) {
  auto pick = [&](std::size_t n) { return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng); };
  std::string s = base;
  static const std::vector<std::string> junk{"x",     "-",   "1e99", "nan", "0", "-3", "layers", "type", "weights",
                                             "99999", "1.5", "tau",  "\"",  "#", "\n", "ctrnn",  "relu", ""};
  switch (pick(7)) {
    case 0: {  // delete a character
      s.erase(pick(s.size()), 1);
      break;
    }
    case 1: {  // replace a character with a byte
      s[pick(s.size())] = static_cast<char>(pick(256));
      break;
    }
    case 2: {  // truncate
      s.resize(pick(s.size()));
      break;
    }
    case 3: {  // insert junk at a random place
      s.insert(pick(s.size()), " " + junk[pick(junk.size())] + " ");
      break;
    }
    case 4: {  // replace a token with junk
      const auto toks = tokens_of(s);
      const std::string& t = toks[pick(toks.size())];
      const std::size_t at = s.find(t);
      s.replace(at, t.size(), junk[pick(junk.size())]);
      break;
    }
    case 5: {  // duplicate a line
      std::vector<std::string> lines;
      std::stringstream ss(s);
      for (std::string l; std::getline(ss, l);) lines.push_back(l);
      const std::size_t k = pick(lines.size());
      lines.insert(lines.begin() + static_cast<std::ptrdiff_t>(k), lines[k]);
      s.clear();
      for (const auto& l : lines) s += l + "\n";
      break;
    }
    default: {  // delete a line
      std::vector<std::string> lines;
      std::stringstream ss(s);
      for (std::string l; std::getline(ss, l);) lines.push_back(l);
      lines.erase(lines.begin() + static_cast<std::ptrdiff_t>(pick(lines.size())));
      s.clear();
      for (const auto& l : lines) s += l + "\n";
      break;
    }
  }
  return s;
}

TEST(NetworkDescription, FourHundredMutantsRejectedWithLocatedErrors) {
  std::mt19937 rng(20261122);
  int rejected = 0, still_valid = 0;
  for (int k = 0; k < 400; ++k) {
    const std::string base = kValidNetworks[k % 3];
    std::string text = mutate(base, rng);
    if (k % 4 == 3) text = mutate(text, rng);  // some get two mutations
    auto d = parse_description(text);
    if (d.ok()) {
      ++still_valid;
      // Still a description: it must build a network that steps.
      auto n = Network::create(d->topology);
      ASSERT_TRUE(n.ok()) << text;
      if (d->weights) {
        ASSERT_TRUE(n.value().set_genome(*d->weights).ok()) << text;
      }
      std::vector<float> x(d->topology.inputs, 0.5f);
      for (float o : n.value().step(x)) ASSERT_TRUE(std::isfinite(o)) << text;
      continue;
    }
    ++rejected;
    ASSERT_TRUE(located_inside_network(d.error(), text)) << "mutant " << k << ": " << d.error() << "\n" << text;
  }
  std::cout << "network description mutants: " << rejected << " rejected with located errors, " << still_valid
            << " still valid\n";
  EXPECT_GT(rejected, 250);
}

}  // namespace
}  // namespace symb::control::network
