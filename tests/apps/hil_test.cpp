// Hardware in the loop through the real `symb` binary: `symb link` makes the pseudo-terminals,
// `symb board` runs the robot's task graph, `symb sim` runs the world, three processes as on a
// bench. Checked:
//  - the HIL run of scenarios/maze.yaml follows the in-process run (`symb run`, same seed) within
//    the tolerance docs/hil.md states: no contacts in either, distance travelled within 15%, and
//    the two paths, compared step by step, at most 3 cm apart on average over the first 15 s;
//  - with 5% of the IR frames corrupted the robot still drives without contacts, and the board's
//    bad-frame count equals exactly the number of frames the injector corrupted;
//  - the board keeps running when the simulator goes away and when it comes back, and says so.
// Real time: 60 s for the comparison in the release build, 15 s under the sanitizers.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "support/eventually.hpp"
#include "support/symb_child.hpp"

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

// At wall-clock pace the HIL run follows the in-process one (compared over kCompareSeconds); in
// lockstep it is the in-process one, over kLockstepSeconds, in a few seconds of wall time.
constexpr int kCompareSeconds = 15;
constexpr int kLockstepSeconds = 60;
#ifdef SYMB_SANITIZER
constexpr int kCorruptSeconds = 10;
#else
constexpr int kCorruptSeconds = 20;
#endif
constexpr int kPathWindowSeconds = 15;  // the paths are compared step by step over this

const std::string kScenario = std::string(SYMB_SCENARIO_DIR) + "/maze.yaml";

// `symb args` as a child process (tests/support/symb_child.hpp).
class Child : public symb::test_support::SymbChild {
 public:
  Child(const std::string& args, fs::path log) : SymbChild(SYMB_BINARY, args, std::move(log)) {}
};

struct Point {
  double x, y;
  bool contact;
};

std::vector<Point> path_of(const fs::path& csv) {
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);  // header
  std::vector<Point> out;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream s(line);
    for (std::string cell; std::getline(s, cell, ',');) f.push_back(cell);
    if (f.size() < 15) continue;
    out.push_back({std::stod(f[2]), std::stod(f[3]), f[14] == "1"});
  }
  return out;
}

double travelled(const std::vector<Point>& p) {
  double d = 0;
  for (std::size_t i = 1; i < p.size(); ++i) d += std::hypot(p[i].x - p[i - 1].x, p[i].y - p[i - 1].y);
  return d;
}

std::size_t contacts(const std::vector<Point>& p) {
  std::size_t n = 0;
  for (const Point& q : p) n += q.contact ? 1 : 0;
  return n;
}

// "key=value" pairs of the line starting with `prefix`.
std::map<std::string, long long> fields(const std::string& text, const std::string& prefix) {
  std::map<std::string, long long> out;
  const auto at = text.find(prefix);
  if (at == std::string::npos) return out;
  std::stringstream s(text.substr(at + prefix.size(), text.find('\n', at) - at - prefix.size()));
  for (std::string kv; s >> kv;)
    if (auto eq = kv.find('='); eq != std::string::npos) out[kv.substr(0, eq)] = std::stoll(kv.substr(eq + 1));
  return out;
}

// The link CSV row of `symb sim`'s summary.txt, by column name.
std::map<std::string, long long> sim_link_stats(const fs::path& summary) {
  std::stringstream s(symb::test_support::read_whole_file(summary));
  std::string line, header;
  std::map<std::string, long long> out;
  while (std::getline(s, line)) {
    if (line.starts_with("robot,frames_sent")) {
      header = line;
      continue;
    }
    if (header.empty() || line.empty()) continue;
    std::stringstream h(header), v(line);
    for (std::string k, x; std::getline(h, k, ',') && std::getline(v, x, ',');)
      if (k != "robot") out[k] = std::stoll(x);
    break;
  }
  return out;
}

class Hil : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("symb-hil-test-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    link_ = std::make_unique<Child>("link --dir '" + (dir_ / "tty").string() + "'", dir_ / "link.log");
    // The link's paths appear once its pseudo-terminals are up.
    symb::testing::eventually([&] { return fs::exists(dir_ / "tty" / "shell"); });
    ASSERT_TRUE(fs::exists(dir_ / "tty" / "shell")) << link_->output();
  }
  void TearDown() override {
    if (link_) {
      link_->interrupt();
      EXPECT_EQ(link_->wait(), 0) << link_->output();
    }
    if (!HasFailure()) fs::remove_all(dir_);
  }
  // Starts a board and waits until its tasks run: frames the simulator sent before the board
  // opened its line would be flushed unread, and the exact counts below could not hold.
  std::unique_ptr<Child> board(const std::string& extra = "") {
    auto b = std::make_unique<Child>("board '" + kScenario + "' --serial '" + (dir_ / "tty" / "board").string() +
                                         "' --shell '" + (dir_ / "tty" / "board-shell").string() + "' " + extra,
                                     dir_ / ("board" + std::to_string(boards_++) + ".log"));
    for (int i = 0; i < 1500 && b->output().find("Ctrl-C to stop") == std::string::npos; ++i)
      std::this_thread::sleep_for(20ms);
    EXPECT_NE(b->output().find("Ctrl-C to stop"), std::string::npos) << b->output();
    return b;
  }
  // The maze with seed 1 for `seconds`: `symb run` into inproc/, then board (with `board_extra`)
  // and `symb sim` (with `sim_extra`) into hil/. The board's output is kept in board_output_.
  void run_both(int seconds, const std::string& sim_extra, const std::string& board_extra = "") {
    const std::string d = "--duration " + std::to_string(seconds) + "s";
    Child run("run '" + kScenario + "' --seed 1 --quiet --out '" + (dir_ / "inproc").string() + "' " + d,
              dir_ / "inproc.log");
    ASSERT_EQ(run.wait(), 0) << run.output();
    auto b = board(board_extra);
    ASSERT_EQ(sim("hil", "--seed 1 " + sim_extra + " " + d), 0) << sim_output_;
    b->interrupt();
    ASSERT_EQ(b->wait(), 0) << b->output();
    board_output_ = b->output();
  }
  int sim(const std::string& out, const std::string& extra) {
    Child c("sim '" + kScenario + "' --serial '" + (dir_ / "tty" / "sim").string() + "' --out '" +
                (dir_ / out).string() + "' --quiet " + extra,
            dir_ / (out + ".log"));
    const int rc = c.wait();
    sim_output_ = c.output();
    return rc;
  }

  fs::path dir_;
  std::unique_ptr<Child> link_;
  std::string sim_output_, board_output_;
  int boards_ = 0;
};

TEST_F(Hil, FollowsTheInProcessRunOfTheMaze) {
  run_both(kCompareSeconds, "");
  ASSERT_FALSE(HasFatalFailure());

  const auto in = path_of(dir_ / "inproc" / "steps.csv");
  const auto hil = path_of(dir_ / "hil" / "steps.csv");
  const std::size_t steps = static_cast<std::size_t>(kCompareSeconds) * 1000 / 30;
  ASSERT_GE(in.size(), steps - 1);
  ASSERT_GE(hil.size(), steps - 1);
  EXPECT_EQ(contacts(in), 0u);
  EXPECT_EQ(contacts(hil), 0u);
  const double din = travelled(in), dhil = travelled(hil);
  EXPECT_GT(din, 10.0) << "the in-process robot hardly moved";
  EXPECT_NEAR(dhil, din, 0.15 * din);
  const std::size_t window = std::min({in.size(), hil.size(), std::size_t{kPathWindowSeconds * 1000 / 30}});
  double sum = 0;
  std::size_t same = 0;
  for (std::size_t i = 0; i < window; ++i) {
    sum += std::hypot(in[i].x - hil[i].x, in[i].y - hil[i].y);
    same += (in[i].x == hil[i].x && in[i].y == hil[i].y) ? 1 : 0;
  }
  const auto link = sim_link_stats(dir_ / "hil" / "summary.txt");
  EXPECT_LT(sum / static_cast<double>(window), 3.0)
      << "identical steps " << same << " of " << window << ", late answers " << link.at("late");
  std::printf("in-process %.1f cm, HIL %.1f cm; first %zu steps: %zu identical, mean distance %.3f cm; late %lld\n",
              din, dhil, window, same, sum / static_cast<double>(window), link.at("late"));
}

// `symb sim --lockstep` with `symb board --lockstep`: the simulator waits for every answer instead
// of the wall clock, and the board's node runs on the frames, so a minute of the maze is the
// in-process run bit for bit however busy the box (a board on the wall clock can still act
// between a frame and its answer: docs/hil.md).
TEST_F(Hil, InLockstepTheRunIsTheInProcessOneBitForBit) {
  run_both(kLockstepSeconds, "--lockstep", "--lockstep");
  ASSERT_FALSE(HasFatalFailure());
  const auto hash = [](const fs::path& summary) {
    const std::string text = symb::test_support::read_whole_file(summary);
    const auto at = text.find("trajectory hash: ");
    return at == std::string::npos ? std::string() : text.substr(at, text.find('\n', at) - at);
  };
  const std::string in = hash(dir_ / "inproc" / "summary.txt");
  ASSERT_FALSE(in.empty());
  EXPECT_EQ(hash(dir_ / "hil" / "summary.txt"), in);
  const std::string hil = symb::test_support::read_whole_file(dir_ / "hil" / "summary.txt");
  EXPECT_NE(hil.find("executor: hardware-in-the-loop, lockstep"), std::string::npos) << hil;
  const auto link = sim_link_stats(dir_ / "hil" / "summary.txt");
  const long long steps = kLockstepSeconds * 1000 / 30;
  EXPECT_EQ(link.at("frames_sent"), steps + 1);  // the handshake and one frame per step
  EXPECT_EQ(link.at("applied"), steps - 1);      // every step after the first, on its answer
  EXPECT_EQ(link.at("late"), 0);
  EXPECT_EQ(link.at("missing"), 1);  // step 1 runs at rest
  EXPECT_EQ(link.at("bad"), 0);
  EXPECT_NE(sim_output_.find("in lockstep with the boards"), std::string::npos) << sim_output_;
  EXPECT_NE(board_output_.find("its clock follows the simulator's frames"), std::string::npos) << board_output_;
  const auto board_stats = fields(board_output_, "board-stats:");
  ASSERT_FALSE(board_stats.empty()) << board_output_;
  EXPECT_EQ(board_stats.at("good"), steps);  // every frame ran the node, none was let go
  EXPECT_EQ(board_stats.at("missed"), 0);
  EXPECT_GE(board_stats.at("handshakes"), 1);  // the simulator sends it again each second until answered
  EXPECT_EQ(board_stats.at("answers"), steps + board_stats.at("handshakes"));
  EXPECT_EQ(board_stats.at("line_open"), 1);
}

// The newest "board: frames N good, M bad (crc C), X missed (S stale)" line of a board's periodic
// statistics: N + M + S, the frames the board read (a stale one was read, then let go for a newer).
long long frames_seen(const std::string& board_output) {
  const auto at = board_output.rfind("board: frames ");
  if (at == std::string::npos) return -1;
  long long good = 0, bad = 0, crc = 0, missed = 0, stale = 0;
  if (std::sscanf(board_output.c_str() + at, "board: frames %lld good, %lld bad (crc %lld), %lld missed (%lld stale)",
                  &good, &bad, &crc, &missed, &stale) != 5)
    return -1;
  return good + bad + stale;
}

TEST_F(Hil, CorruptedFramesAreCountedExactlyAndTheRobotStillNavigates) {
  auto b = board("--stats-every 100ms");
  ASSERT_EQ(sim("hil", "--seed 1 --corrupt 0.05 --duration " + std::to_string(kCorruptSeconds) + "s"), 0)
      << sim_output_;
  const auto sim_stats = sim_link_stats(dir_ / "hil" / "summary.txt");
  ASSERT_FALSE(sim_stats.empty());
  const long long sent = sim_stats.at("frames_sent"), corrupted = sim_stats.at("corrupted");
  // The board is stopped once it has read every frame sent (its statistics say so), not after a
  // guessed while.
  for (int i = 0; i < 1000 && frames_seen(b->output()) < sent; ++i) std::this_thread::sleep_for(10ms);
  b->interrupt();
  ASSERT_EQ(b->wait(), 0) << b->output();
  const std::string board_out = b->output();
  const auto board_stats = fields(board_out, "board-stats:");
  ASSERT_FALSE(board_stats.empty()) << board_out;
  // About 5% of the frames (binomial: 4 standard deviations either way).
  const double expect = 0.05 * static_cast<double>(sent), sd = std::sqrt(expect * 0.95);
  EXPECT_NEAR(static_cast<double>(corrupted), expect, 4 * sd + 1);
  EXPECT_GT(corrupted, 0);
  // Every corrupted frame is exactly one bad frame at the board, and every other one arrives: it is
  // handled, or let go for a newer one when the board fell behind (a box loaded by other tests).
  EXPECT_EQ(board_stats.at("bad"), corrupted) << board_out;
  EXPECT_EQ(board_stats.at("good") + board_stats.at("stale"), sent - corrupted) << board_out;
  EXPECT_EQ(board_stats.at("missed"), corrupted + board_stats.at("stale")) << board_out;
  EXPECT_EQ(board_stats.at("malformed"), 0);
  const auto hil = path_of(dir_ / "hil" / "steps.csv");
  EXPECT_EQ(contacts(hil), 0u);
  EXPECT_GT(travelled(hil), 0.5 * 3.32 * kCorruptSeconds) << "the robot should drive most of the time";
}

TEST_F(Hil, BoardKeepsRunningWhenTheLinkGoesSilentAndComesBack) {
  auto b = board();
  ASSERT_EQ(sim("first", "--duration 2s"), 0) << sim_output_;
  std::this_thread::sleep_for(800ms);  // > 10 control periods of silence
  ASSERT_EQ(sim("second", "--duration 2s"), 0) << sim_output_;
  std::this_thread::sleep_for(300ms);
  b->interrupt();
  ASSERT_EQ(b->wait(), 0) << b->output();
  const std::string out = b->output();
  EXPECT_NE(out.find("link lost: no IR frame"), std::string::npos) << out;
  EXPECT_NE(out.find("the simulator started anew"), std::string::npos) << out;
  EXPECT_NE(out.find("link back after"), std::string::npos) << out;
  const auto s = fields(out, "board-stats:");
  EXPECT_GE(s.at("losses"), 1);
  EXPECT_GE(s.at("recoveries"), 1);
  // Both runs were answered: the second simulator drove the robot too.
  const auto second = path_of(dir_ / "second" / "steps.csv");
  EXPECT_GT(travelled(second), 2.0);
}

// `symb link` stopped and started again mid-run (the cable, or a USB adapter, pulled and plugged
// back): both sides notice, reopen their paths and go on; the run completes and says how long its
// line was down.
TEST_F(Hil, BothSidesReopenTheirLinesWhenTheLinkComesBack) {
  auto b = board("--stats-every 100ms");
  Child sim("sim '" + kScenario + "' --serial '" + (dir_ / "tty" / "sim").string() + "' --out '" +
                (dir_ / "back").string() + "' --quiet --duration 6s",
            dir_ / "back.log");
  // The run is under way once the board has read a second of frames (its statistics say so).
  for (int i = 0; i < 1000 && frames_seen(b->output()) < 34; ++i) std::this_thread::sleep_for(10ms);
  ASSERT_GE(frames_seen(b->output()), 34) << b->output();
  link_->interrupt();
  ASSERT_EQ(link_->wait(), 0) << link_->output();
  std::this_thread::sleep_for(500ms);  // the outage: no link at all
  link_ = std::make_unique<Child>("link --dir '" + (dir_ / "tty").string() + "'", dir_ / "link2.log");
  ASSERT_EQ(sim.wait(), 0) << sim.output();
  const auto link = sim_link_stats(dir_ / "back" / "summary.txt");
  EXPECT_EQ(link.at("line_losses"), 1) << sim.output();
  EXPECT_EQ(link.at("line_reopens"), 1) << sim.output();
  EXPECT_EQ(link.at("line_open"), 1);
  EXPECT_GE(link.at("line_down_ms"), 400);
  EXPECT_GT(link.at("unsent"), 0);
  EXPECT_NE(sim.output().find("open again after"), std::string::npos) << sim.output();
  b->interrupt();
  ASSERT_EQ(b->wait(), 0) << b->output();
  const auto s = fields(b->output(), "board-stats:");
  EXPECT_EQ(s.at("line_losses"), 1) << b->output();
  EXPECT_EQ(s.at("line_reopens"), 1) << b->output();
  EXPECT_GE(s.at("line_down_ms"), 400);
  // The board answered after the line came back: the simulator applied frames in the last second.
  const auto hil = path_of(dir_ / "back" / "steps.csv");
  ASSERT_GT(hil.size(), 170u);
  const Point end = hil.back(), before = hil[hil.size() - 34];
  EXPECT_GT(std::hypot(end.x - before.x, end.y - before.y), 1.0) << "the robot should drive again";
}

// A link that never comes back: both sides report the run as failed, with the time it was down.
TEST_F(Hil, ADeadLinkFailsBothSides) {
  auto b = board("--stats-every 100ms");
  Child sim("sim '" + kScenario + "' --serial '" + (dir_ / "tty" / "sim").string() + "' --out '" +
                (dir_ / "dead").string() + "' --quiet --duration 3s",
            dir_ / "dead.log");
  // The run is under way once the board has read a second of frames (its statistics say so).
  for (int i = 0; i < 1000 && frames_seen(b->output()) < 34; ++i) std::this_thread::sleep_for(10ms);
  ASSERT_GE(frames_seen(b->output()), 34) << b->output();
  link_->interrupt();
  ASSERT_EQ(link_->wait(), 0) << link_->output();
  link_.reset();
  EXPECT_EQ(sim.wait(), 1) << sim.output();
  EXPECT_NE(sim.output().find("dead link"), std::string::npos) << sim.output();
  const std::string summary = symb::test_support::read_whole_file(dir_ / "dead" / "summary.txt");
  EXPECT_NE(summary.find("dead link: the serial line was down at the end of the run"), std::string::npos) << summary;
  const auto link = sim_link_stats(dir_ / "dead" / "summary.txt");
  EXPECT_EQ(link.at("line_open"), 0);
  EXPECT_GE(link.at("line_down_ms"), 1000);
  EXPECT_GT(link.at("unsent"), 0);
  b->interrupt();
  EXPECT_EQ(b->wait(), 1) << b->output();
  EXPECT_NE(b->output().find("was down when the board stopped"), std::string::npos) << b->output();
}

// The board on the frames has the wall-clock board's line handling: a line that goes away is
// reopened with backoff, and one still down at the end fails the board, with its figures. Here
// the simulator keeps the wall-clock pace (a board on the frames serves either kind).
TEST_F(Hil, ABoardOnTheFramesReopensItsLineAndADeadOneFailsIt) {
  auto b = board("--lockstep --stats-every 100ms");
  Child sim("sim '" + kScenario + "' --serial '" + (dir_ / "tty" / "sim").string() + "' --out '" +
                (dir_ / "dead").string() + "' --quiet --duration 3s",
            dir_ / "dead.log");
  const auto frames = [&] {
    const std::string out = b->output();
    const auto at = out.rfind("board: frames ");
    long long n = -1;
    if (at != std::string::npos) std::sscanf(out.c_str() + at, "board: frames %lld good", &n);
    return n;
  };
  for (int i = 0; i < 1000 && frames() < 34; ++i) std::this_thread::sleep_for(10ms);
  ASSERT_GE(frames(), 34) << b->output();
  link_->interrupt();
  ASSERT_EQ(link_->wait(), 0) << link_->output();
  link_.reset();
  EXPECT_EQ(sim.wait(), 1) << sim.output();
  b->interrupt();
  EXPECT_EQ(b->wait(), 1) << b->output();
  const std::string out = b->output();
  EXPECT_NE(out.find("reopening it with backoff"), std::string::npos) << out;
  EXPECT_NE(out.find("was down when the board stopped"), std::string::npos) << out;
  const auto s = fields(out, "board-stats:");
  ASSERT_FALSE(s.empty()) << out;
  EXPECT_EQ(s.at("line_open"), 0);
  EXPECT_EQ(s.at("line_losses"), 1);
  EXPECT_EQ(s.at("line_reopens"), 0);
  EXPECT_GE(s.at("good"), 34);
  EXPECT_EQ(s.at("answers") + s.at("not_taken"), s.at("good") + s.at("handshakes") + s.at("restarts"));
}

}  // namespace
