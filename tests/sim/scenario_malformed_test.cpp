// Malformed scenarios by seeded mutation of the shipped files: lines deleted, duplicated,
// swapped or re-indented, the text truncated, bytes flipped, values replaced by ones of the wrong
// type. Each mutant either parses into a scenario that still obeys the rules (robots inside the
// arena and clear of walls and each other, hooks between existing tasks), or is rejected with
// "file:LINE:COLUMN: message" where LINE is a line the mutant has. None may crash.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "symb/kernel/random_stream.hpp"
#include "symb/sim/scenario.hpp"

namespace symb::sim {
namespace {

namespace fs = std::filesystem;

constexpr int kMutantsPerFile = 300;

std::vector<std::pair<std::string, std::string>> shipped_files() {
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& e : fs::directory_iterator(SYMB_SCENARIO_DIR))
    if (e.path().extension() == ".yaml") {
      std::ifstream in(e.path());
      std::stringstream ss;
      ss << in.rdbuf();
      out.emplace_back(e.path().filename().string(), ss.str());
    }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::string> split_lines(const std::string& s) {
  std::vector<std::string> lines;
  std::string cur;
  for (char c : s) {
    if (c == '\n') {
      lines.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (!cur.empty()) lines.push_back(cur);
  return lines;
}

std::string join(const std::vector<std::string>& lines) {
  std::string s;
  for (const auto& l : lines) s += l + "\n";
  return s;
}

// Lines a text has, as an editor counts them (at least one).
int line_count(const std::string& s) {
  int n = static_cast<int>(std::count(s.begin(), s.end(), '\n'));
  if (!s.empty() && s.back() != '\n') ++n;
  return std::max(n, 1);
}

const char* const kWrongValues[] = {
    "abc",   "-1",     "[1, 2]", "{a: 1}", "",   "~",      "1e999", "nan", "\"", "0", "99999999999999999999",
    "-> ->", "random", "true",   "&a",     "*b", "!!int x"};
const char kNoise[] = ":-[]{},#&*!|>'\"%@` \t\n0123456789abcxyz.";

std::string mutate(const std::string& text, kernel::RandomStream& rng) {
  auto lines = split_lines(text);
  auto pick = [&](std::size_t n) { return static_cast<std::size_t>(rng.below(n)); };
  if (lines.empty()) return text;
  switch (rng.below(9)) {
    case 0:  // delete a line
      lines.erase(lines.begin() + static_cast<std::ptrdiff_t>(pick(lines.size())));
      return join(lines);
    case 1: {  // duplicate a line
      const std::size_t i = pick(lines.size());
      lines.insert(lines.begin() + static_cast<std::ptrdiff_t>(i), lines[i]);
      return join(lines);
    }
    case 2:  // swap two lines
      std::swap(lines[pick(lines.size())], lines[pick(lines.size())]);
      return join(lines);
    case 3: {  // re-indent a line
      std::string& l = lines[pick(lines.size())];
      if (rng.below(2) == 0)
        l.insert(0, std::string(1 + pick(4), ' '));
      else
        l.erase(0, std::min(l.find_first_not_of(' '), 1 + pick(4)));
      return join(lines);
    }
    case 4:  // truncate
      return text.substr(0, pick(text.size()));
    case 5: {  // flip bytes
      std::string s = text;
      const std::size_t n = 1 + pick(4);
      for (std::size_t k = 0; k < n; ++k) {
        const std::size_t at = pick(s.size());
        s[at] = rng.below(2) == 0 ? static_cast<char>(s[at] ^ (1 << rng.below(8))) : kNoise[pick(sizeof(kNoise) - 1)];
      }
      return s;
    }
    case 6: {  // a value of the wrong type after some "key:"
      std::vector<std::size_t> with_value;
      for (std::size_t i = 0; i < lines.size(); ++i) {
        const auto c = lines[i].find(": ");
        if (c != std::string::npos && lines[i].find('#') > c) with_value.push_back(i);
      }
      if (with_value.empty()) return text;
      std::string& l = lines[with_value[pick(with_value.size())]];
      l = l.substr(0, l.find(": ") + 2) + kWrongValues[pick(std::size(kWrongValues))];
      return join(lines);
    }
    case 7: {  // a number inside a line changed to something out of range
      std::string& l = lines[pick(lines.size())];
      const auto d = l.find_first_of("0123456789");
      if (d == std::string::npos) return text;
      l.insert(d, rng.below(2) == 0 ? "-" : "9999");
      return join(lines);
    }
    default: {  // an unknown key, or a known one misspelt
      const std::size_t i = pick(lines.size());
      const std::string& l = lines[i];
      const std::string indent = l.substr(0, l.find_first_not_of(" -"));
      lines.insert(lines.begin() + static_cast<std::ptrdiff_t>(i),
                   indent + (rng.below(2) == 0 ? "colour: red" : "heigth: 5"));
      return join(lines);
    }
  }
}

// What an accepted mutant must still satisfy.
void expect_sound(const Scenario& sc) {
  if (sc.world_kind == WorldKind::kMujoco) {  // no arena: the modules' own rules
    ASSERT_FALSE(sc.robots.empty());
    for (std::size_t i = 0; i < sc.robots.size(); ++i)
      for (std::size_t j = 0; j < i; ++j) EXPECT_NE(sc.robots[i].name, sc.robots[j].name);
    for (const auto& d : sc.organism.docked) EXPECT_NE(d.a, d.b);
    return;
  }
  const WorldSpec& w = sc.world;
  EXPECT_TRUE(std::isfinite(w.width) && w.width > 0 && std::isfinite(w.height) && w.height > 0);
  ASSERT_FALSE(sc.robots.empty());
  for (const auto& wall : w.walls) {
    EXPECT_GE(std::min({wall.x1, wall.x2}), 0);
    EXPECT_LE(std::max({wall.x1, wall.x2}), w.width);
    EXPECT_GE(std::min({wall.y1, wall.y2}), 0);
    EXPECT_LE(std::max({wall.y1, wall.y2}), w.height);
  }
  for (const RobotSpec& r : sc.robots) ASSERT_TRUE(std::isfinite(r.start.x) && std::isfinite(r.start.y)) << r.name;
  // Names unique and starts apart, checked in O(n log n): a shipped swarm has a thousand robots,
  // and every accepted mutant of it comes here.
  std::set<std::string> names;
  for (const RobotSpec& r : sc.robots) EXPECT_TRUE(names.insert(r.name).second) << r.name;
  std::vector<std::size_t> by_x(sc.robots.size());
  for (std::size_t i = 0; i < by_x.size(); ++i) by_x[i] = i;
  std::sort(by_x.begin(), by_x.end(),
            [&](std::size_t a, std::size_t b) { return sc.robots[a].start.x < sc.robots[b].start.x; });
  std::size_t too_close = 0;
  for (std::size_t k = 0; k < by_x.size(); ++k) {
    const Pose& p = sc.robots[by_x[k]].start;
    for (std::size_t m = k + 1; m < by_x.size() && sc.robots[by_x[m]].start.x - p.x < 2 * kStartClearance; ++m) {
      const Pose& q = sc.robots[by_x[m]].start;
      too_close += std::hypot(q.x - p.x, q.y - p.y) < 2 * kStartClearance ? 1 : 0;
    }
  }
  EXPECT_EQ(too_close, 0u) << "pairs of robots starting closer than " << 2 * kStartClearance << " cm";
  for (std::size_t i = 0; i < sc.robots.size(); ++i) {
    const RobotSpec& r = sc.robots[i];
    EXPECT_GE(std::min({r.start.x, r.start.y, w.width - r.start.x, w.height - r.start.y}), kStartClearance);
    for (const auto& h : r.hooks) {
      EXPECT_NE(h.from, h.to);
      for (const std::string* end : {&h.from, &h.to}) {
        const bool known = is_device_task_name(*end) || std::any_of(r.tasks.begin(), r.tasks.end(),
                                                                    [&](const TaskSpec& t) { return t.name == *end; });
        EXPECT_TRUE(known) << *end;
      }
    }
  }
}

// "file:LINE:COLUMN: " with 1 <= LINE <= lines; returns false (with a reason) otherwise.
::testing::AssertionResult located(const std::string& error, const std::string& file, int lines) {
  if (error.rfind(file + ":", 0) != 0) return ::testing::AssertionFailure() << "no file prefix: " << error;
  std::size_t i = file.size() + 1;
  auto number = [&](long& out) {
    const std::size_t s = i;
    while (i < error.size() && std::isdigit(static_cast<unsigned char>(error[i]))) ++i;
    if (i == s || i - s > 9) return false;
    out = std::stol(error.substr(s, i - s));
    return true;
  };
  long line = 0, column = 0;
  if (!number(line) || i >= error.size() || error[i++] != ':' || !number(column))
    return ::testing::AssertionFailure() << "no LINE:COLUMN: " << error;
  if (error.compare(i, 2, ": ") != 0 || error.size() <= i + 2)
    return ::testing::AssertionFailure() << "no message: " << error;
  if (line < 1 || line > lines || column < 1)
    return ::testing::AssertionFailure() << "line " << line << " of " << lines << ", column " << column << ": "
                                         << error;
  return ::testing::AssertionSuccess();
}

TEST(ScenarioMalformed, MutantsOfTheShippedFilesAreRejectedWithALocationOrStaySound) {
  const auto files = shipped_files();
  ASSERT_GE(files.size(), 4u);
  int total = 0, rejected = 0;
  kernel::RandomStream rng(20240607, 1);
  // A 3D scenario's module kind files, beside it.
  ScenarioParseOptions beside;
  beside.read_module_kind = [](std::string_view path) -> kernel::Result<std::string> {
    std::ifstream in(std::string(SYMB_SCENARIO_DIR) + "/" + std::string(path));
    if (!in) return kernel::Error{"no such file"};
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  };
  for (const auto& [name, text] : files) {
    ASSERT_TRUE(parse_scenario(text, name, beside).ok()) << name;
    for (int k = 0; k < kMutantsPerFile; ++k) {
      std::string m = mutate(text, rng);
      // Some mutants get a second or third mutation, so that errors pile up.
      for (int extra = static_cast<int>(rng.below(3)); extra > 0; --extra) m = mutate(m, rng);
      if (m == text) continue;
      ++total;
      auto sc = parse_scenario(m, name, beside);
      if (sc.ok()) {
        SCOPED_TRACE(m);
        expect_sound(*sc);
      } else {
        ++rejected;
        EXPECT_TRUE(located(sc.error(), name, line_count(m))) << "--- mutant of " << name << " ---\n" << m;
      }
    }
  }
  std::cout << total << " mutants, " << rejected << " rejected\n";
  EXPECT_GE(total, 1000);
  // A deleted comment line or a swapped pair of walls leaves a valid file; most mutants do not.
  EXPECT_GT(rejected, total * 6 / 10);
}

}  // namespace
}  // namespace symb::sim
