// 1,000 malformed MDL2e programs, made by seeded mutation of valid ones (deleted, duplicated and
// swapped tokens, random bytes, truncation, unknown names, bad numbers): every one is rejected
// with an error of the form "LINE:COLUMN: message" that points inside the text, and none crashes.
// A mutant that happens to still be a valid program (two sibling atoms swapped, say) is not
// counted; it must compile, round-trip through byte code and run.
#include <iostream>
#include <random>
#include <regex>

#include <gtest/gtest.h>

#include "symb/control/mdl2e/lexer.hpp"

#include "mdl2e_test_support.hpp"

namespace symb::control::mdl2e {
namespace {

const char* kValidMdl2e[] = {
    R"(sensor ir[7]
interrupt obstacle_left  = ir[0] > 2000
interrupt obstacle_front = ir[2] > 2000
interrupt obstacle_right = ir[4] > 2000
interrupt bumped = external
plan avoid_obstacles {
  task start obstacle_logger
  behaviour explore loop until bumped {
    atom forward(100) until obstacle_left or obstacle_front or obstacle_right
    atom turn(-80) for 2s until not obstacle_left
    atom turn(80) for 2s until not (obstacle_front or obstacle_right)
  }
  atom backward(50) for 500ms
  task suspend obstacle_logger
})",
    R"(sensor ir[7]
interrupt too_close  = ir[4] > 3000
interrupt too_far    = ir[4] < 1000
interrupt wall_ahead = ir[2] > 2500
behaviour veer_left for 1s { atom wheels(60, 100) }
behaviour veer_right for 1s { atom wheels(100, 60) }
plan follow_right_wall loop for 60s {
  atom forward(100) until too_close or too_far or wall_ahead
  atom turn(60) until not wall_ahead
  do veer_left until not too_close
  do veer_right until not too_far
})",
    R"(interrupt x = external
interrupt y = external
plan p loop 3 for 10s until x and not y {
  behaviour outer for 500ms { atom stop for 1ms behaviour inner loop 2 { atom wheels(-1.5, 2) until y } }
  task delete helper
})",
};

struct Piece {
  std::string text;
  bool number = false;
  bool ident = false;
};

std::vector<Piece> pieces(std::string_view src) {
  auto toks = lex(src);
  std::vector<Piece> out;
  if (!toks) return out;
  for (const auto& t : *toks) {
    if (t.kind == TokenKind::kEnd) break;
    out.push_back(
        {std::string(t.text) + std::string(t.suffix), t.kind == TokenKind::kNumber, t.kind == TokenKind::kIdent});
  }
  return out;
}

std::string join(const std::vector<Piece>& ps, std::mt19937& rng) {
  std::string s;
  for (const auto& p : ps) {
    if (!s.empty()) s += (rng() % 5 == 0) ? "\n" : " ";
    s += p.text;
  }
  return s;
}

std::string mutate_mdl2e(std::mt19937& rng, int& kind) {
  const std::string base = kValidMdl2e[rng() % std::size(kValidMdl2e)];
  auto ps = pieces(base);
  const std::size_t n = ps.size();
  auto pick = [&] { return static_cast<std::size_t>(rng() % n); };
  kind = static_cast<int>(rng() % 8);
  switch (kind) {
    case 0: ps.erase(ps.begin() + static_cast<long>(pick())); break;  // delete
    case 1: {                                                         // duplicate
      const std::size_t i = pick();
      ps.insert(ps.begin() + static_cast<long>(i), ps[i]);
      break;
    }
    case 2: {  // swap two tokens
      const std::size_t i = pick(), j = pick();
      std::swap(ps[i], ps[j]);
      break;
    }
    case 3: {  // random bytes spliced into the text
      std::string s = join(ps, rng);
      const std::size_t at = rng() % (s.size() + 1);
      std::string junk;
      for (int k = 0, m = 1 + static_cast<int>(rng() % 4); k < m; ++k) junk += static_cast<char>(rng() % 256);
      s.insert(at, junk);
      return s;
    }
    case 4: {  // truncation
      std::string s = join(ps, rng);
      return s.substr(0, rng() % s.size());
    }
    case 5: {  // unknown name
      std::vector<std::size_t> ids;
      for (std::size_t i = 0; i < n; ++i)
        if (ps[i].ident) ids.push_back(i);
      ps[ids[rng() % ids.size()]].text = "zq" + std::to_string(rng() % 1000);
      break;
    }
    case 6: {  // bad number
      static const char* bad[] = {"1e999", "12abc", "99999999999999", "0x10", "1..2",
                                  "3.",    "-",     "1.5e3",          "007q", "4000001s"};
      std::vector<std::size_t> nums;
      for (std::size_t i = 0; i < n; ++i)
        if (ps[i].number) nums.push_back(i);
      if (nums.empty()) return join(ps, rng) + " 1e999";
      ps[nums[rng() % nums.size()]].text = bad[rng() % std::size(bad)];
      break;
    }
    default: {  // a random token replaced by random punctuation
      static const char* punct[] = {"{", "}", "(", ")", "[", "]", ",", "=", "<", ">=", "-", "plan", "atom"};
      ps[pick()].text = punct[rng() % std::size(punct)];
      break;
    }
  }
  return join(ps, rng);
}

bool located_inside_mdl2e(const std::string& error, const std::string& src) {
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

TEST(Mdl2eMalformed, ValidBasesCompile) {
  for (const char* v : kValidMdl2e) (void)testing::must_compile(v);
}

TEST(Mdl2eMalformed, ThousandMutantsRejectedWithLocatedErrors) {
  std::mt19937 rng(20261122);
  int rejected = 0, still_valid = 0;
  std::array<int, 8> by_kind{};
  for (int attempt = 0; rejected < 1000 && attempt < 5000; ++attempt) {
    int kind = 0;
    const std::string src = mutate_mdl2e(rng, kind);
    auto r = compile_source(src);
    if (r.ok()) {
      ++still_valid;
      auto back = decode(encode(*r));
      ASSERT_TRUE(back.ok()) << src;
      Interpreter in(*back);
      for (int t = 0; t < 20; ++t)
        (void)in.step(testing::ms(t * 100), InterruptInputs{{}, static_cast<std::uint64_t>(t)});
      continue;
    }
    ++rejected;
    ++by_kind[static_cast<std::size_t>(kind)];
    ASSERT_TRUE(located_inside_mdl2e(r.error(), src)) << "error '" << r.error() << "' for:\n" << src;
  }
  std::cout << "mdl2e mutants: " << rejected << " rejected with located errors, " << still_valid
            << " still valid (compiled, round-tripped, ran)\n";
  EXPECT_EQ(rejected, 1000);
  EXPECT_LT(still_valid, 200) << "too many mutants are still valid programs";
  for (int k = 0; k < 8; ++k) EXPECT_GT(by_kind[static_cast<std::size_t>(k)], 50) << "mutation kind " << k;
}

}  // namespace
}  // namespace symb::control::mdl2e
