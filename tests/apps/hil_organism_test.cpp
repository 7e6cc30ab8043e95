// Hardware in the loop in 3D through the real `symb` binary: `symb link` makes the
// pseudo-terminals, `symb board --robot m4` runs the tail module of scenarios/organism_chain.yaml,
// `symb sim --board m4` runs the other four modules and the world, three processes as on a bench.
// Checked: in lockstep the organism's trajectory hash equals `symb run`'s (the same run, bit for
// bit); at wall-clock pace with 5% of the sensor frames corrupted the run completes and the
// board's bad-frame count equals the injector's count exactly; a wrong or missing --board is a
// usage error naming the modules, and --board on a 2D scenario is refused. Over DDS instead of the
// pseudo-terminals (--dds), the lockstep run is `symb run`'s too.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <utility>

#include <gtest/gtest.h>

#include "support/eventually.hpp"
#include "support/symb_child.hpp"

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

const std::string kChain = std::string(SYMB_SCENARIO_DIR) + "/organism_chain.yaml";

// `symb args` as a child process (tests/support/symb_child.hpp).
class Hil3Child : public symb::test_support::SymbChild {
 public:
  Hil3Child(const std::string& args, fs::path log) : SymbChild(SYMB_BINARY, args, std::move(log)) {}
};

// The value after "KEY: " on its line, or empty.
std::string hil3_line_value(const std::string& text, const std::string& key) {
  const auto at = text.find(key + ": ");
  if (at == std::string::npos) return {};
  const auto from = at + key.size() + 2;
  return text.substr(from, text.find('\n', from) - from);
}

// "key=value" pairs of the line starting with `prefix`.
std::map<std::string, long long> hil3_fields(const std::string& text, const std::string& prefix) {
  std::map<std::string, long long> out;
  const auto at = text.find(prefix);
  if (at == std::string::npos) return out;
  std::stringstream s(text.substr(at + prefix.size(), text.find('\n', at) - at - prefix.size()));
  for (std::string kv; s >> kv;)
    if (auto eq = kv.find('='); eq != std::string::npos) out[kv.substr(0, eq)] = std::stoll(kv.substr(eq + 1));
  return out;
}

// The good frames in the board's latest statistics line ("board: frames N good, ..."), or -1.
long long hil3_board_frames(const std::string& board_output) {
  const auto at = board_output.rfind("board: frames ");
  long long good = -1;
  if (at == std::string::npos || std::sscanf(board_output.c_str() + at, "board: frames %lld good", &good) != 1)
    return -1;
  return good;
}

class Hil3Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("symb-hil3-test-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    link_ = std::make_unique<Hil3Child>("link --dir '" + (dir_ / "tty").string() + "'", dir_ / "link.log");
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
  std::unique_ptr<Hil3Child> board(const std::string& extra = "") {
    auto b = std::make_unique<Hil3Child>(
        "board '" + kChain + "' --robot m4 --quiet --serial '" + (dir_ / "tty" / "board").string() + "' " + extra,
        dir_ / "board.log");
    for (int i = 0; i < 1500 && b->output().find("Ctrl-C to stop") == std::string::npos; ++i)
      std::this_thread::sleep_for(20ms);
    EXPECT_NE(b->output().find("Ctrl-C to stop"), std::string::npos) << b->output();
    return b;
  }

  fs::path dir_;
  std::unique_ptr<Hil3Child> link_;
};

TEST_F(Hil3Cli, InLockstepTheOrganismIsTheInProcessOneBitForBit) {
  Hil3Child run("run '" + kChain + "' --quiet --duration 3s --out '" + (dir_ / "inproc").string() + "'",
                dir_ / "inproc.log");
  ASSERT_EQ(run.wait(), 0) << run.output();
  auto b = board();
  Hil3Child sim("sim '" + kChain + "' --board m4 --lockstep --quiet --duration 3s --serial '" +
                    (dir_ / "tty" / "sim").string() + "' --out '" + (dir_ / "hil").string() + "'",
                dir_ / "hil.log");
  ASSERT_EQ(sim.wait(), 0) << sim.output();
  b->interrupt();
  ASSERT_EQ(b->wait(), 0) << b->output();
  const std::string in = symb::test_support::read_whole_file(dir_ / "inproc" / "summary.txt");
  const std::string hil = symb::test_support::read_whole_file(dir_ / "hil" / "summary.txt");
  const std::string in_hash = hil3_line_value(in, "trajectory hash");
  ASSERT_FALSE(in_hash.empty()) << in;
  EXPECT_EQ(hil3_line_value(hil, "trajectory hash"), in_hash) << hil;
  const auto link = hil3_fields(hil, "link-stats:");
  EXPECT_EQ(link.at("sent"), 101);  // the handshake and 100 ticks
  EXPECT_EQ(link.at("applied"), 99);
  EXPECT_EQ(link.at("late"), 0);
  EXPECT_EQ(link.at("bad"), 0);
  const auto bs = hil3_fields(b->output(), "board-stats:");
  EXPECT_EQ(bs.at("good"), 100);
  EXPECT_EQ(bs.at("bad"), 0);
  EXPECT_EQ(bs.at("missed"), 0);
}

TEST_F(Hil3Cli, CorruptedFramesAreCountedExactlyAtWallClockPace) {
  auto b = board();
  Hil3Child sim("sim '" + kChain + "' --board m4 --corrupt 0.05 --quiet --duration 4s --serial '" +
                    (dir_ / "tty" / "sim").string() + "' --out '" + (dir_ / "hil").string() + "'",
                dir_ / "hil.log");
  ASSERT_EQ(sim.wait(), 0) << sim.output();
  b->interrupt();
  ASSERT_EQ(b->wait(), 0) << b->output();
  const auto link = hil3_fields(symb::test_support::read_whole_file(dir_ / "hil" / "summary.txt"), "link-stats:");
  const auto bs = hil3_fields(b->output(), "board-stats:");
  std::printf("3D HIL at 5%% corruption: sent %lld, corrupted %lld, board bad %lld, good %lld, late %lld\n",
              link.at("sent"), link.at("corrupted"), bs.at("bad"), bs.at("good"), link.at("late"));
  EXPECT_GT(link.at("corrupted"), 0);
  EXPECT_EQ(bs.at("bad"), link.at("corrupted"));
  EXPECT_EQ(bs.at("good") + bs.at("bad"), link.at("sent") - 1);  // the handshake is not counted good
  EXPECT_GT(link.at("applied"), 100);
}

// `symb link` stopped in the middle of a run and started again 0.5 s later: both sides reopen
// their paths, the simulator exits 0, and the board's module answers again.
TEST_F(Hil3Cli, BothSidesReopenTheirLinesWhenTheLinkComesBack) {
  auto b = board("--stats-every 100ms");
  Hil3Child sim("sim '" + kChain + "' --board m4 --quiet --duration 5s --serial '" + (dir_ / "tty" / "sim").string() +
                    "' --out '" + (dir_ / "back").string() + "'",
                dir_ / "back.log");
  // The run is under way once the board has read a second of frames (its statistics say so): a
  // simulator slow to start on a loaded machine must have opened its line before the link stops.
  for (int i = 0; i < 2000 && hil3_board_frames(b->output()) < 34; ++i) std::this_thread::sleep_for(10ms);
  ASSERT_GE(hil3_board_frames(b->output()), 34) << b->output();
  link_->interrupt();
  ASSERT_EQ(link_->wait(), 0) << link_->output();
  std::this_thread::sleep_for(500ms);  // the outage: no link at all
  link_ = std::make_unique<Hil3Child>("link --dir '" + (dir_ / "tty").string() + "'", dir_ / "link2.log");
  ASSERT_EQ(sim.wait(), 0) << sim.output();
  const auto link = hil3_fields(symb::test_support::read_whole_file(dir_ / "back" / "summary.txt"), "link-stats:");
  EXPECT_EQ(link.at("line_losses"), 1) << sim.output();
  EXPECT_EQ(link.at("line_reopens"), 1) << sim.output();
  EXPECT_EQ(link.at("line_open"), 1);
  EXPECT_GE(link.at("line_down_ms"), 400);
  EXPECT_GT(link.at("unsent"), 0);
  EXPECT_NE(sim.output().find("open again after"), std::string::npos) << sim.output();
  b->interrupt();
  ASSERT_EQ(b->wait(), 0) << b->output();
  const auto bs = hil3_fields(b->output(), "board-stats:");
  EXPECT_EQ(bs.at("line_losses"), 1) << b->output();
  EXPECT_EQ(bs.at("line_reopens"), 1) << b->output();
  EXPECT_EQ(bs.at("line_open"), 1);
  // The board answered after the line came back: more than the ticks before the outage were
  // applied (about a second, 34 ticks; the run is 166).
  EXPECT_GT(link.at("applied"), 100) << sim.output();
  std::printf("3D HIL, link stopped for 0.5 s: sim down %lld ms, %lld unsent, %lld applied of 166 ticks\n",
              link.at("line_down_ms"), link.at("unsent"), link.at("applied"));
}

TEST(Hil3CliUsage, TheBoardsModuleIsNamedAndChecked) {
  const fs::path log = fs::temp_directory_path() / ("symb-hil3-usage-" + std::to_string(::getpid()) + ".log");
  {
    Hil3Child c("sim '" + kChain + "' --serial /nonexistent/tty", log);
    EXPECT_EQ(c.wait(), 2);
    EXPECT_NE(c.output().find("needs --board NAME"), std::string::npos) << c.output();
  }
  {
    Hil3Child c("sim '" + kChain + "' --serial /nonexistent/tty --board m9", log);
    EXPECT_EQ(c.wait(), 2);
    EXPECT_NE(c.output().find("no module 'm9' (it has m0, m1, m2, m3, m4)"), std::string::npos) << c.output();
  }
  {
    Hil3Child c("board '" + kChain + "' --serial /nonexistent/tty --robot m9", log);
    EXPECT_EQ(c.wait(), 2);
    EXPECT_NE(c.output().find("no module 'm9'"), std::string::npos) << c.output();
  }
  {
    Hil3Child c("sim '" + std::string(SYMB_SCENARIO_DIR) + "/maze.yaml' --serial /nonexistent/tty --board r1", log);
    EXPECT_EQ(c.wait(), 2);
    EXPECT_NE(c.output().find("--board and --dds are for 3D scenarios"), std::string::npos) << c.output();
  }
  {
    // An event on the board's module: refused at its place in the file, before any line is opened.
    Hil3Child c("sim '" + kChain + "' --serial /nonexistent/tty --board m0", log);
    EXPECT_EQ(c.wait(), 1);
    EXPECT_NE(c.output().find("organism_chain.yaml:"), std::string::npos) << c.output();
  }
  const std::pair<std::string, std::string> dds_cases[] = {
      {"sim '" + kChain + "' --board m4 --dds --serial /nonexistent/tty", "--dds or --serial"},
      {"sim '" + kChain + "' --board m4 --serial /nonexistent/tty --domain 3", "--domain is for --dds"},
      {"sim '" + kChain + "' --board m4 --dds --domain 233", "--domain"},
      {"sim '" + kChain + "' --board m4 --dds --lease 0s", "--lease: '0s' is out of range"},
      {"board '" + kChain + "' --robot m4 --dds --serial /nonexistent/tty", "--dds or --serial"},
      {"board '" + kChain + "' --robot m4 --prefix 'a b' --dds", "--prefix 'a b': not a name"},
      {"sim '" + std::string(SYMB_SCENARIO_DIR) + "/maze.yaml' --dds", "--dds are for 3D scenarios"},
  };
  for (const auto& [args, says] : dds_cases) {
    Hil3Child c(args, log);
    EXPECT_EQ(c.wait(), 2) << args << "\n" << c.output();
    EXPECT_NE(c.output().find(says), std::string::npos) << args << "\n" << c.output();
  }
  fs::remove(log);
}

// The board's module in another process over DDS (`--dds` on both sides: the split world's frame
// stream, rt/<prefix>/m4/to_robot and .../to_world, found by discovery with no configuration).
// In lockstep the organism is `symb run`'s bit for bit, and the board ends when the simulator's
// run does. Release build only, as the other DDS process tests.
TEST(Hil3Dds, InLockstepOverDdsTheOrganismIsTheInProcessOneBitForBit) {
#ifdef SYMB_SANITIZER
  GTEST_SKIP() << "processes over DDS: release build only";
#endif
  const fs::path dir = fs::temp_directory_path() / ("symb-hil3-dds-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string prefix = "hil3_" + std::to_string(::getpid());
  const std::string bus =
      " --dds --domain " + std::to_string(10 + ::getpid() % 200) + " --prefix " + prefix + " --lease 300ms";
  Hil3Child run("run '" + kChain + "' --quiet --duration 3s --out '" + (dir / "inproc").string() + "'",
                dir / "inproc.log");
  ASSERT_EQ(run.wait(), 0) << run.output();
  Hil3Child board("board '" + kChain + "' --robot m4 --quiet" + bus, dir / "board.log");
  Hil3Child sim("sim '" + kChain + "' --board m4 --lockstep --quiet --duration 3s" + bus + " --out '" +
                    (dir / "hil").string() + "'",
                dir / "hil.log");
  ASSERT_EQ(sim.wait(), 0) << sim.output();
  ASSERT_EQ(board.wait(), 0) << board.output();
  EXPECT_NE(board.output().find("board m4: the simulator ended its run"), std::string::npos) << board.output();
  const std::string in = symb::test_support::read_whole_file(dir / "inproc" / "summary.txt");
  const std::string hil = symb::test_support::read_whole_file(dir / "hil" / "summary.txt");
  const std::string in_hash = hil3_line_value(in, "trajectory hash");
  ASSERT_FALSE(in_hash.empty()) << in;
  std::printf("in process %s, module m4 over DDS %s\n", in_hash.c_str(),
              hil3_line_value(hil, "trajectory hash").c_str());
  EXPECT_EQ(hil3_line_value(hil, "trajectory hash"), in_hash) << hil;
  EXPECT_NE(hil.find("transport: DDS rt/" + prefix + "/m4/to_world"), std::string::npos) << hil;
  const auto link = hil3_fields(hil, "link-stats:");
  EXPECT_EQ(link.at("applied"), 99);
  EXPECT_EQ(link.at("late"), 0);
  EXPECT_EQ(link.at("bad"), 0);
  EXPECT_EQ(link.at("line_open"), 1);
  const auto bs = hil3_fields(board.output(), "board-stats:");
  EXPECT_EQ(bs.at("good"), 100);
  EXPECT_EQ(bs.at("bad"), 0);
  EXPECT_EQ(bs.at("missed"), 0);
  if (!::testing::Test::HasFailure()) fs::remove_all(dir);
}

}  // namespace
