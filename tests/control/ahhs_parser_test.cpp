// The AHHS description text: the shipped network, the round trip through to_text(), located
// errors for each kind of mistake, and a few hundred seeded mutations of valid descriptions, every
// one rejected with "LINE:COLUMN: message" pointing inside the text (or still valid, then it runs).
#include <fstream>
#include <iostream>
#include <random>
#include <regex>
#include <sstream>

#include <gtest/gtest.h>

#include "symb/control/ahhs/model.hpp"
#include "symb/control/ahhs/parser.hpp"

namespace symb::control::ahhs {
namespace {

std::string shipped(const std::string& name) {
  std::ifstream f(std::string(SYMB_SHIPPED_SCENARIO_DIR) + "/ahhs/" + name);
  std::stringstream s;
  s << f.rdbuf();
  EXPECT_FALSE(s.str().empty()) << name;
  return s.str();
}

TEST(AhhsParser, ShippedTwoHormoneNetwork) {
  auto n = parse_network(shipped("two_hormone.ahhs"));
  ASSERT_TRUE(n.ok()) << n.error();
  EXPECT_EQ(n->compartments, 2u);
  ASSERT_EQ(n->hormones.size(), 2u);
  EXPECT_EQ(n->hormones[0].name, "obstacle");
  EXPECT_FLOAT_EQ(n->hormones[1].base, 0.5f);
  EXPECT_EQ(n->sensor_count(), 5u);
  EXPECT_EQ(n->actuator_count(), 2u);
  EXPECT_EQ(n->rules.size(), 9u);
  auto back = parse_network(to_text(*n));
  ASSERT_TRUE(back.ok()) << back.error() << "\n" << to_text(*n);
  EXPECT_TRUE(*n == *back);
}

TEST(AhhsParser, InlineStatementsCommentsAndDefaults) {
  auto n = parse_network(
      "compartments 3; link 0 1 # a comment; not a statement\nlink 1 2\n"
      "hormone h base 0.25 diffusion 0.5 min -1 max 2 start 0.5; hormone g\n"
      "rule nonlinear h -> g centre 0 width 0.5 dependent -1e-2 in 2");
  ASSERT_TRUE(n.ok()) << n.error();
  EXPECT_EQ(n->links.size(), 2u);
  EXPECT_FLOAT_EQ(n->hormones[0].min, -1.0f);
  EXPECT_FLOAT_EQ(n->hormones[1].start, 0.0f);
  EXPECT_EQ(n->rules[0].compartment, 2);
  EXPECT_FLOAT_EQ(n->rules[0].dependent, -0.01f);
  EXPECT_FLOAT_EQ(n->rules[0].fixed, 0.0f);
}

TEST(AhhsParser, ErrorsPointAtTheToken) {
  const std::pair<const char*, const char*> cases[] = {
      {"", "1:1: empty description"},
      {"hormone h", "1:1: declare the compartments first"},
      {"compartments 0", "1:14: a network has at least one compartment"},
      {"compartments 2\ncompartments 2", "2:1: compartments declared twice"},
      {"compartments 2\nlink 0 2", "2:8: a compartment must be at most 1"},
      {"compartments 2\nlink 1 1", "2:8: a compartment cannot be its own neighbour"},
      {"compartments 2\nlink 0 1\nlink 1 0", "3:1: this link is given twice"},
      {"compartments 1\nhormone 9h", "2:9: a hormone name"},
      {"compartments 1\nhormone h decay 1.5", "2:17: decay must be 0 to 1"},
      {"compartments 1\nhormone h base nan", "2:16: 'base' must be a finite number"},
      {"compartments 1\nhormone h colour 3", "2:11: unknown key 'colour'"},
      {"compartments 1\nhormone h base", "2:15: 'base' needs a value"},
      {"compartments 1\nhormone h min 1 max 0", "2:21: max must be above min"},
      {"compartments 3\nlink 0 1\nlink 1 2\nhormone h diffusion 0.6", "4:21: diffusion times the largest"},
      {"compartments 1\nhormone h\nhormone h", "3:9: hormone 'h' declared twice"},
      {"compartments 1\nsensor 40 in 0", "2:8: a sensor index must be at most 31"},
      {"compartments 1\nsensor 0 at 0", "2:10: expected 'in'"},
      {"compartments 1\nsensor 0 in 0 extra", "2:15: unexpected 'extra'"},
      {"compartments 1\nactuator 1 in 0\nhormone h", "2:10: actuators are numbered 0 to 0"},
      {"compartments 1\nhormone h\nrule magic h -> h centre 0 width 1", "3:6: unknown rule kind 'magic'"},
      {"compartments 1\nhormone h\nrule hormone h => h centre 0 width 1", "3:16: expected '->'"},
      {"compartments 1\nhormone h\nrule hormone g -> h centre 0 width 1", "3:14: no hormone named 'g'"},
      {"compartments 1\nhormone h\nrule sensor 0 -> h centre 0 width 1", "3:13: sensor 0 is not placed"},
      {"compartments 1\nhormone h\nrule actuator h -> 0 centre 0 width 1", "3:20: actuator 0 is not placed"},
      {"compartments 1\nhormone h\nrule hormone h -> h width 1", "3:1: the rule needs 'centre X'"},
      {"compartments 1\nhormone h\nrule hormone h -> h centre 0 width 1 in 1", "3:41: a compartment must be at most 0"},
      {"compartments 1\nsensor 0 in 0\nhormone h\nrule sensor 0 -> h centre 0 width 1 in 0", "4:37: unknown key 'in'"},
      {"compartments 1\nhormone h\nrule hormone h ->", "3:18: incomplete"},
      {"compartments 1\nfoo", "2:1: unknown statement 'foo'"},
      {"compartments 1\nhormone h \x01", "2:11: unexpected character"},
  };
  for (const auto& [text, expected] : cases) {
    auto n = parse_network(text);
    ASSERT_FALSE(n.ok()) << text;
    EXPECT_EQ(n.error().rfind(expected, 0), 0u) << "text:\n" << text << "\ngot: " << n.error();
  }
}

const char* kValidAhhs[] = {
    R"(compartments 2
link 0 1
hormone obstacle base 0 decay 0.2 diffusion 0.05
hormone drive base 0.5 decay 0 diffusion 0
sensor 0 in 0
sensor 1 in 0
sensor 3 in 1
actuator 0 in 1
actuator 1 in 0
rule sensor 0 -> obstacle centre 1 width 1 fixed 1
rule sensor 3 -> obstacle centre 1 width 1 fixed 1
rule actuator drive -> 0 centre 1 width 1 fixed 1
rule actuator obstacle -> 1 centre 1 width 1 fixed -2
)",
    R"(compartments 4
link 0 1
link 1 2
link 2 3
hormone a base 0.01 decay 0.1 diffusion 0.3 min -1 max 1 start 0
hormone b base 0 decay 0.05 diffusion 0.1
hormone c
sensor 0 in 3
actuator 0 in 0
rule hormone a -> b centre 0.5 width 0.5 fixed 0.1 dependent -1 in 2
rule nonlinear b -> c centre 0 width 2 dependent 0.5
rule sensor 0 -> a centre 0.5 width 0.5 fixed 0.2 dependent 1
rule actuator c -> 0 centre 0.5 width 1 fixed 1 dependent -2
)",
};

using Lines = std::vector<std::vector<std::string>>;

Lines split(const std::string& text) {
  Lines out;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::vector<std::string> w;
    std::string x;
    while (words >> x) w.push_back(x);
    if (!w.empty()) out.push_back(w);
  }
  return out;
}

std::string join(const Lines& ls) {
  std::string s;
  for (const auto& l : ls) {
    for (std::size_t k = 0; k < l.size(); ++k) s += (k ? " " : "") + l[k];
    s += "\n";
  }
  return s;
}

std::string mutate_ahhs(std::mt19937& rng, int& kind) {
  Lines ls = split(kValidAhhs[rng() % std::size(kValidAhhs)]);
  auto line = [&]() -> std::vector<std::string>& { return ls[rng() % ls.size()]; };
  kind = static_cast<int>(rng() % 8);
  switch (kind) {
    case 0: {  // delete a token
      auto& l = line();
      l.erase(l.begin() + static_cast<long>(rng() % l.size()));
      break;
    }
    case 1: {  // duplicate a token
      auto& l = line();
      const std::size_t i = rng() % l.size();
      l.insert(l.begin() + static_cast<long>(i), l[i]);
      break;
    }
    case 2: {  // swap two tokens of one line
      auto& l = line();
      std::swap(l[rng() % l.size()], l[rng() % l.size()]);
      break;
    }
    case 3: {  // random bytes
      std::string s = join(ls);
      std::string junk;
      for (int k = 0, m = 1 + static_cast<int>(rng() % 4); k < m; ++k) junk += static_cast<char>(rng() % 256);
      s.insert(rng() % (s.size() + 1), junk);
      return s;
    }
    case 4: {  // truncation, or a line moved to the front
      if (rng() % 2) {
        const std::string s = join(ls);
        return s.substr(0, rng() % s.size());
      }
      std::rotate(ls.begin(), ls.begin() + static_cast<long>(1 + rng() % (ls.size() - 1)), ls.end());
      break;
    }
    case 5: {  // an unknown name
      auto& l = line();
      l[rng() % l.size()] = "zq" + std::to_string(rng() % 1000);
      break;
    }
    case 6: {  // a bad number
      static const char* bad[] = {"1e999", "12abc", "99999999999", "0x10", "1..2", "-", "inf", "-0.5", "7", "1e-46x"};
      auto& l = line();
      l[rng() % l.size()] = bad[rng() % std::size(bad)];
      break;
    }
    default: {  // a keyword in the wrong place
      static const char* words[] = {"->", "in", "rule", "hormone", "link", "centre", "width", ";", "#", "sensor"};
      auto& l = line();
      l[rng() % l.size()] = words[rng() % std::size(words)];
      break;
    }
  }
  return join(ls);
}

bool located_inside_ahhs(const std::string& error, const std::string& src) {
  static const std::regex re(R"(^(\d+):(\d+): .+)");
  std::smatch m;
  if (!std::regex_match(error, m, re)) return false;
  const long line = std::stol(m[1]), col = std::stol(m[2]);
  std::vector<std::size_t> lens{0};
  for (char c : src) {
    if (c == '\n')
      lens.push_back(0);
    else
      ++lens.back();
  }
  if (line < 1 || line > static_cast<long>(lens.size())) return false;
  return col >= 1 && col <= static_cast<long>(lens[static_cast<std::size_t>(line - 1)]) + 1;
}

TEST(AhhsParser, FiveHundredMutantsRejectedWithLocatedErrors) {
  for (const char* v : kValidAhhs) ASSERT_TRUE(parse_network(v).ok()) << parse_network(v).error();
  std::mt19937 rng(20261122);
  int rejected = 0, still_valid = 0;
  std::array<int, 8> by_kind{};
  for (int attempt = 0; rejected < 500 && attempt < 3000; ++attempt) {
    int kind = 0;
    const std::string src = mutate_ahhs(rng, kind);
    auto n = parse_network(src);
    if (n.ok()) {
      ++still_valid;
      auto m = Model::create(*n);
      ASSERT_TRUE(m.ok()) << m.error() << "\n" << src;
      const float s[4] = {0.1f, 0.5f, 0.9f, 1.0f};
      for (int t = 0; t < 20; ++t) m.value().step(s);
      continue;
    }
    ++rejected;
    ++by_kind[static_cast<std::size_t>(kind)];
    ASSERT_TRUE(located_inside_ahhs(n.error(), src)) << "error '" << n.error() << "' for:\n" << src;
  }
  std::cout << "ahhs mutants: " << rejected << " rejected with located errors, " << still_valid
            << " still valid (ran)\n";
  EXPECT_EQ(rejected, 500);
  EXPECT_LT(still_valid, 300);
  for (int k = 0; k < 8; ++k) EXPECT_GT(by_kind[static_cast<std::size_t>(k)], 20) << "mutation kind " << k;
}

}  // namespace
}  // namespace symb::control::ahhs
