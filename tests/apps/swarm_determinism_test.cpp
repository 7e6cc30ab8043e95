// The swarm demo: same seed, same trace hash (in one process, and across separate runs of the
// `symb` binary); the robots really move and stay inside the arena; and the command line turns
// every bad argument into exit code 2 with a message that names it.
#include <sys/wait.h>

#include <array>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>

#include <gtest/gtest.h>

#include "symb/apps/cli_args.hpp"
#include "symb/apps/swarm/swarm_demo.hpp"

namespace symb::apps {
namespace {

using namespace std::chrono_literals;

struct Outcome {
  int exit_code = -1;
  std::string output;  // stdout, or stdout and stderr when the command merged them
};

// Runs a shell command line, collecting its stdout.
Outcome run(const std::string& command) {
  Outcome o;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return o;
  std::array<char, 4096> buf{};
  std::size_t n = 0;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) o.output.append(buf.data(), n);
  const int status = pclose(pipe);
  o.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return o;
}

std::string symb_command(const std::string& args) { return std::string("'") + SYMB_BINARY + "' " + args; }

SwarmOptions small_swarm(std::uint64_t seed) {
  SwarmOptions o;
  o.nodes = 100;
  o.seed = seed;
  o.duration = 3s;
  return o;
}

std::uint64_t hash_of(const SwarmOptions& o) {
  auto r = run_swarm(o);
  EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error());
  return r.ok() ? r->trace_hash : 0;
}

TEST(SwarmDeterminism, SameSeedSameHashDifferentSeedDifferentHash) {
  const std::uint64_t a = hash_of(small_swarm(7));
  const std::uint64_t b = hash_of(small_swarm(7));
  const std::uint64_t c = hash_of(small_swarm(8));
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
}

TEST(SwarmDeterminism, SameHashAcrossProcessRestarts) {
  const std::string command = symb_command("demo swarm --nodes 100 --seed 7 --duration 3s --print-hash --quiet");
  const Outcome first = run(command);
  const Outcome second = run(command);
  ASSERT_EQ(first.exit_code, 0) << first.output;
  ASSERT_EQ(second.exit_code, 0) << second.output;
  const std::string expected = "trace-hash: " + hex64(hash_of(small_swarm(7))) + "\n";
  // Nothing but the hash line on stdout.
  EXPECT_EQ(first.output, expected);
  EXPECT_EQ(second.output, expected);
}

TEST(SwarmBehaviour, RobotsMoveAndStayInsideTheArena) {
  SwarmOptions o = small_swarm(3);
  o.duration = 5s;
  auto r = run_swarm(o);
  ASSERT_TRUE(r.ok()) << r.error();
  ASSERT_EQ(r->robots.size(), 100u);
  double total = 0;
  std::uint64_t poses = 0, contacts = 0;
  for (const RobotFigures& f : r->robots) {
    EXPECT_GE(f.min_x, 0.0);
    EXPECT_GE(f.min_y, 0.0);
    EXPECT_LE(f.max_x, o.arena);
    EXPECT_LE(f.max_y, o.arena);
    // 0.25 m/s cruising for 5 s, minus turns and slowing down near walls.
    EXPECT_GT(f.path_length, 0.3);
    EXPECT_LT(f.path_length, 5 * 0.5 + 0.01);  // never faster than the wheel speed limit
    // 100 Hz kinematics for 5 s, plus the pose sent at start.
    EXPECT_NEAR(static_cast<double>(f.poses), 501.0, 1.0);
    total += f.path_length;
    poses += f.poses;
    contacts += f.contact_poses;
  }
  EXPECT_GT(total / 100, 0.8);
  // The controller avoids walls: robots touch one in only a small share of their poses.
  EXPECT_LT(static_cast<double>(contacts), 0.05 * static_cast<double>(poses));
  // Per robot and second: 100 poses each to proximity and trail, 33 readings, 33 wheel commands.
  EXPECT_GT(r->traffic.delivered, 100u * 5 * 260);
  EXPECT_EQ(r->traffic.dropped(), 0u);
  EXPECT_FALSE(r->node0_log.empty());
  EXPECT_TRUE(r->files.empty());  // no out_dir: nothing written
}

TEST(SwarmBehaviour, WritesTheOutputFolder) {
  const auto dir = std::filesystem::path(::testing::TempDir()) / "symb_swarm_outputs";
  std::filesystem::remove_all(dir);
  SwarmOptions o = small_swarm(5);
  o.nodes = 10;
  o.duration = 1s;
  o.out_dir = dir;
  auto r = run_swarm(o);
  ASSERT_TRUE(r.ok()) << r.error();
  ASSERT_EQ(r->files.size(), 3u);
  for (const char* name : {"trajectories.svg", "summary.txt", "syslog.txt"})
    EXPECT_TRUE(std::filesystem::is_regular_file(dir / name)) << name;
  std::ifstream summary(dir / "summary.txt");
  std::stringstream text;
  text << summary.rdbuf();
  EXPECT_NE(text.str().find("trace hash: " + hex64(r->trace_hash)), std::string::npos) << text.str();
  std::ifstream svg(dir / "trajectories.svg");
  std::stringstream picture;
  picture << svg.rdbuf();
  EXPECT_NE(picture.str().find("<polyline"), std::string::npos);
  EXPECT_NE(picture.str().find("</svg>"), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(SwarmBehaviour, RunsOnThreadsInRealTime) {
  // Not deterministic, so only: it runs, robots move, it shuts down cleanly (TSan checks the rest).
  SwarmOptions o;
  o.nodes = 4;
  o.duration = 300ms;
  o.realtime = true;
  auto r = run_swarm(o);
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_GT(r->traffic.delivered, 0u);
  for (const RobotFigures& f : r->robots) EXPECT_GT(f.poses, 0u);
}

TEST(SwarmOptionsCheck, RefusesOutOfRange) {
  SwarmOptions o;
  o.nodes = 0;
  EXPECT_FALSE(run_swarm(o).ok());
  o.nodes = kMaxSwarmNodes + 1;
  EXPECT_FALSE(run_swarm(o).ok());
  o.nodes = 1;
  o.duration = 0s;
  EXPECT_FALSE(run_swarm(o).ok());
}

// --- command line -----------------------------------------------------------------------------

struct BadInput {
  const char* args;
  const char* named;  // what the message must mention
};

// Readable in test listings (ctest shows it) instead of a byte dump.
void PrintTo(const BadInput& b, std::ostream* out) {
  *out << "symb";
  if (*b.args != '\0') *out << ' ' << b.args;
}

std::string test_name(const ::testing::TestParamInfo<BadInput>& info) {
  std::string name = std::to_string(info.index) + "_";
  for (char c : std::string_view(info.param.args)) name += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return name;
}

class SymbBadInput : public ::testing::TestWithParam<BadInput> {};

TEST_P(SymbBadInput, ExitsWithTwoAndNamesTheArgument) {
  const BadInput& bad = GetParam();
  // stdout to /dev/null, stderr into the pipe: the message must be on stderr.
  const Outcome o = run(symb_command(bad.args) + " 2>&1 >/dev/null");
  EXPECT_EQ(o.exit_code, 2) << bad.args << "\n" << o.output;
  EXPECT_NE(o.output.find(bad.named), std::string::npos) << bad.args << "\n" << o.output;
}

INSTANTIATE_TEST_SUITE_P(
    Cli, SymbBadInput,
    ::testing::Values(
        BadInput{"dmeo", "'dmeo' (did you mean 'demo'?)"}, BadInput{"", "missing command"},
        BadInput{"demo", "missing demo name"}, BadInput{"demo swram", "'swram' (did you mean 'swarm'?)"},
        BadInput{"demo swarm --nodes 0", "--nodes: '0' is out of range"},
        BadInput{"demo swarm --nodes -3", "--nodes: '-3'"}, BadInput{"demo swarm --nodes abc", "--nodes: 'abc'"},
        BadInput{"demo swarm --nodes 99999999999", "--nodes: '99999999999' is out of range"},
        BadInput{"demo swarm --nodes 99999999999999999999999", "--nodes: '99999999999999999999999' is out of range"},
        BadInput{"demo swarm --nodes", "--nodes needs a value"},
        BadInput{"demo swarm --nodes --quiet", "--nodes needs a value"},
        BadInput{"demo swarm --nodes=", "--nodes needs a value"},
        BadInput{"demo swarm --out ''", "--out needs a value"},
        BadInput{"demo swarm --node 5", "'--node' (did you mean '--nodes'?)"},
        BadInput{"demo swarm --frobnicate", "'--frobnicate'"},
        BadInput{"demo swarm extra", "unexpected argument 'extra'"}, BadInput{"demo swarm --seed -1", "--seed: '-1'"},
        BadInput{"demo swarm --seed 18446744073709551616", "--seed: '18446744073709551616' is out of range"},
        BadInput{"demo swarm --duration 10", "--duration: '10'"},
        BadInput{"demo swarm --duration 0s", "--duration: '0s' is out of range"},
        BadInput{"demo swarm --duration 5parsecs", "--duration: '5parsecs'"},
        BadInput{"demo swarm --quiet=yes", "--quiet takes no value"},
        BadInput{"demo swarm --realtime --nodes 1000", "--nodes: with --realtime"},
        BadInput{"demo swarm --shell-port 0", "--shell-port needs --realtime"},
        BadInput{"demo swarm --realtime --shell-port 70000", "--shell-port: '70000' is out of range"},
        BadInput{"shell", "symb shell"}, BadInput{"shell --tcp nohost", "symb shell"},
        BadInput{"version now", "unexpected argument 'now'"},
        BadInput{"--verison", "'--verison' (did you mean '--version'?)"}, BadInput{"serve", "--node NAME is required"},
        BadInput{"serve --node", "--node needs a value"},
        BadInput{"serve --node m0 --hook bogus", "--hook 'bogus': expected SENDER>RECEIVER[:PORT]"},
        BadInput{"serve --node m0 --domain 999", "--domain: '999' is out of range"},
        BadInput{"evolve --collect", "--collect needs at least one DIR"}),
    test_name);

TEST(SymbCli, HelpAndVersionSucceed) {
  for (const char* args : {"--help", "help", "demo --help", "demo swarm --help", "version", "--version"}) {
    const Outcome o = run(symb_command(args));
    EXPECT_EQ(o.exit_code, 0) << args;
    EXPECT_FALSE(o.output.empty()) << args;
  }
  EXPECT_NE(run(symb_command("demo swarm --help")).output.find("--nodes N"), std::string::npos);
}

TEST(SymbCli, WritesTheOutputFolderAndSaysWhere) {
  const auto dir = std::filesystem::path(::testing::TempDir()) / "symb_cli_swarm";
  std::filesystem::remove_all(dir);
  const Outcome o = run(symb_command("demo swarm --nodes 5 --duration 500ms --quiet --out '" + dir.string() + "'"));
  ASSERT_EQ(o.exit_code, 0) << o.output;
  EXPECT_NE(o.output.find(dir.string()), std::string::npos) << o.output;
  EXPECT_TRUE(std::filesystem::is_regular_file(dir / "trajectories.svg"));
  std::filesystem::remove_all(dir);
}

TEST(SymbCli, UnwritableOutputFolderFailsWithOne) {
  const Outcome o = run(symb_command("demo swarm --nodes 1 --duration 10ms --quiet --out /dev/null/x 2>&1"));
  EXPECT_EQ(o.exit_code, 1) << o.output;
  EXPECT_NE(o.output.find("/dev/null/x"), std::string::npos) << o.output;
}

}  // namespace
}  // namespace symb::apps
