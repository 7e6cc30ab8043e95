// `symb evolve --islands` under mpirun (an island per rank, champions migrating along a ring; a
// rank killed mid-run; (mu+1) islands) and the job array's local fallback (scripts/evolve_array)
// merged by `symb evolve --collect`. Release build only: MPI's processes and the array's are many
// programs, not threads of ours.
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "support/symb_child.hpp"

namespace {

namespace fs = std::filesystem;
using symb::test_support::read_whole_file;

class IslandsTest : public ::testing::Test {
 protected:
  void SetUp() override {
#ifdef SYMB_SANITIZER
    GTEST_SKIP() << "MPI and job arrays: release build only";
#endif
    if (std::system("command -v mpirun > /dev/null 2>&1") != 0) GTEST_SKIP() << "no mpirun (Debian openmpi-bin)";
    dir_ = fs::temp_directory_path() / ("islands_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    if (!dir_.empty()) fs::remove_all(dir_, ec);
  }
  // Runs a shell command line, its output into `log`; its exit status.
  int sh(const std::string& command, const std::string& log) {
    symb::test_support::SymbChild child("/bin/sh", "-c '" + command + "'", dir_ / log);
    const int status = child.wait();
    last_output_ = child.output();
    return status;
  }
  // `symb evolve --islands` under mpirun, as root too (the box's CI runs as root).
  static std::string mpirun(int ranks, const std::string& mpirun_options) {
    return "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 timeout 120 mpirun --oversubscribe --mca btl "
           "self,vader --mca oob_tcp_if_include lo " +
           mpirun_options + " -np " + std::to_string(ranks) + " " + SYMB_BINARY + " evolve ";
  }
  // The maze (or another scenario) for 10 min per island.
  std::string islands(int ranks, const std::string& out, const std::string& extra,
                      const std::string& scenario = std::string(SYMB_SCENARIO_DIR) + "/evolve_maze.yaml") {
    const std::string command = mpirun(ranks, "") + scenario +
                                " --islands --duration 10min --checkpoint-every 0 --quiet --out " +
                                (dir_ / out).string() + " " + extra;
    EXPECT_EQ(sh(command, out + ".log"), 0) << last_output_;
    return read_whole_file(dir_ / out / "islands.txt");
  }
  // The pid of the `symb` process of MPI rank `rank` writing into `out`, or -1.
  static pid_t rank_process(const fs::path& out, int rank) {
    const std::string want = "OMPI_COMM_WORLD_RANK=" + std::to_string(rank);
    for (const auto& entry : fs::directory_iterator("/proc")) {
      const std::string name = entry.path().filename().string();
      if (name.find_first_not_of("0123456789") != std::string::npos) continue;
      if (read_whole_file(entry.path() / "comm").rfind("symb", 0) != 0) continue;
      if (read_whole_file(entry.path() / "cmdline").find(out.string()) == std::string::npos) continue;
      std::string env = read_whole_file(entry.path() / "environ");
      for (char& c : env)
        if (c == '\0') c = '\n';
      if (("\n" + env).find("\n" + want + "\n") != std::string::npos) return std::stoi(name);
    }
    return -1;
  }
  static std::size_t lines(const fs::path& file) {
    const std::string text = read_whole_file(file);
    return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
  }
  // Three islands of 3 h under `mpirun --enable-recovery`; `victim` is killed (SIGKILL) once its
  // fitness.csv has 99 evaluations (on disk as they come). Returns islands.txt.
  std::string kill_one_of_three(int victim) {
    const fs::path out = dir_ / ("killed_" + std::to_string(victim));
    symb::test_support::SymbChild run(
        "/bin/sh",
        "-c '" + mpirun(3, "--enable-recovery") + SYMB_SCENARIO_DIR +
            "/evolve_maze.yaml --islands --duration 3h --checkpoint-every 0 --quiet --seed 5 --migrate-every 2min "
            "--migrant-wait 3s --out " +
            out.string() + "'",
        dir_ / ("killed_" + std::to_string(victim) + ".log"));
    const fs::path csv = out / ("island_" + std::to_string(victim)) / "fitness.csv";
    pid_t pid = -1;
    for (int i = 0; i < 3000 && (pid < 0 || lines(csv) < 100); ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      if (pid < 0) pid = rank_process(out, victim);
    }
    EXPECT_GT(pid, 0) << "no process for rank " << victim;
    if (pid > 0) ::kill(pid, SIGKILL);
    EXPECT_EQ(run.wait(), 0) << run.output();  // mpirun --enable-recovery: 0 whatever the ranks say
    last_output_ = run.output();
    return read_whole_file(out / "islands.txt");
  }
  static std::string hash_of(const std::string& text, const std::string& label) {
    std::smatch m;
    if (std::regex_search(text, m, std::regex(label + ": ([0-9a-f]{16})"))) return m[1];
    return "";
  }
  fs::path dir_;
  std::string last_output_;
};

TEST_F(IslandsTest, TwoAndFourRanksGiveTheSameResultTwiceForASeed) {
  for (int ranks : {2, 4}) {
    const std::string a = islands(ranks, "a" + std::to_string(ranks), "--seed 5 --migrate-every 2min");
    const std::string b = islands(ranks, "b" + std::to_string(ranks), "--seed 5 --migrate-every 2min");
    ASSERT_FALSE(hash_of(a, "islands hash").empty()) << a;
    // Byte for byte, but for the output folder named in the best island's line.
    const std::regex folder(R"(\(/[^)]*/(island_\d+/champion.genome)\))");
    EXPECT_EQ(std::regex_replace(a, folder, "$1"), std::regex_replace(b, folder, "$1")) << a << b;
    EXPECT_NE(a.find(std::to_string(ranks) + " ranks, migration every 120 s"), std::string::npos) << a;
    // 10 min at a migration every 2 min: 4 migrants taken by every island (the 5th exchange is at the end).
    const std::regex row(R"(\n(\d+)  (\d+)  (\d+)  (\d+)  )");
    int islands_seen = 0;
    for (auto it = std::sregex_iterator(a.begin(), a.end(), row); it != std::sregex_iterator(); ++it) {
      EXPECT_EQ((*it)[2].str(), std::to_string(5 + islands_seen)) << "seed = base + rank";
      EXPECT_EQ((*it)[4].str(), "4") << a;
      ++islands_seen;
    }
    EXPECT_EQ(islands_seen, ranks) << a;
  }
}

// A rank killed mid-run: the other islands run to the end (3 h: 514 evaluations each), the ring
// skips the dead one from the exchange after its migrant was found missing, and the report names it.
TEST_F(IslandsTest, ARankKilledMidRunLeavesTheOthersToFinishAndIsNamed) {
  const std::string report = kill_one_of_three(1);
  EXPECT_NE(last_output_.find("no migrant from rank 1"), std::string::npos) << last_output_;
  EXPECT_NE(last_output_.find("island 1 gone; the other 2 finished"), std::string::npos) << last_output_;
  EXPECT_TRUE(std::regex_search(report, std::regex(R"(\n1  6  gone: its migrant for exchange (\d+) \(at [0-9.]+ min\) )"
                                                   R"(never came; the ring skipped it from exchange \d+; island_1/)")))
      << report;
  const std::regex finished(R"(\n(0|2)  (5|7)  514  (\d+)  (\d+)  [0-9.]+  [0-9a-f]{16})");
  EXPECT_EQ(std::distance(std::sregex_iterator(report.begin(), report.end(), finished), std::sregex_iterator()), 2)
      << report;
  EXPECT_NE(report.find("gone: island 1 (killed"), std::string::npos) << report;
  // Everything the survivors accepted is on disk; the dead one keeps what it wrote.
  const fs::path out = dir_ / "killed_1";
  for (int r : {0, 2}) {
    EXPECT_EQ(lines(out / ("island_" + std::to_string(r)) / "fitness.csv"), 515u) << r;
    EXPECT_TRUE(fs::exists(out / ("island_" + std::to_string(r)) / "champion.genome")) << r;
  }
  EXPECT_GE(lines(out / "island_1" / "fitness.csv"), 100u);
  EXPECT_FALSE(fs::exists(out / "island_1" / "summary.txt"));
}

// Rank 0 killed: the first rank still there (1) writes the report.
TEST_F(IslandsTest, WhenRankZeroDiesTheNextRankWritesTheReport) {
  const std::string report = kill_one_of_three(0);
  EXPECT_NE(report.find("\n0  5  gone: "), std::string::npos) << report << last_output_;
  EXPECT_NE(report.find("written by rank 1: the ranks below it are gone"), std::string::npos) << report;
  EXPECT_NE(report.find("\n1  6  514  "), std::string::npos) << report;
  EXPECT_NE(report.find("\n2  7  514  "), std::string::npos) << report;
}

// An island whose run fails (its folder cannot be made) leaves the ring at once; the others finish
// and the report, written before anyone exits (plain mpirun stops the job at the first failure),
// says which failed.
TEST_F(IslandsTest, AFailedIslandIsReportedAndTheOthersFinish) {
  const fs::path out = dir_ / "failing";
  fs::create_directories(out);
  std::ofstream(out / "island_1") << "a file where island 1's folder goes\n";
  EXPECT_NE(sh(mpirun(3, "") + SYMB_SCENARIO_DIR +
                   "/evolve_maze.yaml --islands --duration 10min --checkpoint-every 0 --quiet --seed 5 "
                   "--migrate-every 2min --out " +
                   out.string(),
               "failing.log"),
            0);
  EXPECT_NE(last_output_.find("rank 1: cannot create"), std::string::npos) << last_output_;
  const std::string report = read_whole_file(out / "islands.txt");
  EXPECT_NE(report.find("\n1  6  failed"), std::string::npos) << report << last_output_;
  EXPECT_NE(report.find("\n0  5  28  "), std::string::npos) << report;
  EXPECT_NE(report.find("\n2  7  28  "), std::string::npos) << report;
  EXPECT_NE(report.find("failed: island 1"), std::string::npos) << report;
}

// (mu+1)-ONLINE islands: the maze with its evolution task swapped for mu_plus_one. A migrant is
// evaluated as a child and enters the population by replacing the worst member when better.
TEST_F(IslandsTest, MuPlusOneIslandsTakeMigrantsAndAreDeterministic) {
  std::string yaml = read_whole_file(std::string(SYMB_SCENARIO_DIR) + "/evolve_maze.yaml");
  const std::string from = "type: one_plus_one\n        params: {evaluation: 20s, recovery: 1s, sigma_min: 0.05,";
  const auto at = yaml.find(from);
  ASSERT_NE(at, std::string::npos) << "evolve_maze.yaml changed: update this test";
  yaml.replace(at, from.size(),
               "type: mu_plus_one\n        params: {evaluation: 20s, recovery: 1s, mu: 5, sigma: 0.5,");
  const fs::path scenario = dir_ / "evolve_maze_mu.yaml";
  std::ofstream(scenario) << yaml;
  const std::string a = islands(2, "mu_a", "--seed 3 --migrate-every 2min", scenario.string());
  const std::string b = islands(2, "mu_b", "--seed 3 --migrate-every 2min", scenario.string());
  ASSERT_FALSE(hash_of(a, "islands hash").empty()) << a;
  EXPECT_EQ(hash_of(a, "islands hash"), hash_of(b, "islands hash")) << a << b;
  // 10 min, a migration every 2 min: 4 migrants each; the population (5 of 21 s) is full after
  // 105 s, so every migrant is evaluated, and some replace a worse member.
  const std::regex row(R"(\n(\d+)  (\d+)  (\d+)  (\d+)  (\d+)  )");
  int islands_seen = 0;
  std::uint64_t taken = 0;
  for (auto it = std::sregex_iterator(a.begin(), a.end(), row); it != std::sregex_iterator(); ++it, ++islands_seen) {
    EXPECT_EQ((*it)[4].str(), "4") << a;
    EXPECT_LE(std::stoull((*it)[5].str()), 4u) << a;
    taken += std::stoull((*it)[5].str());
  }
  EXPECT_EQ(islands_seen, 2) << a;
  EXPECT_GT(taken, 0u) << "no migrant entered a population: " << a;
  EXPECT_NE(read_whole_file(dir_ / "mu_a" / "island_0" / "summary.txt").find("evolution task: thymio/evolution"),
            std::string::npos);
}

TEST_F(IslandsTest, AnIslandWithoutMigrationIsTheSingleRunOfItsSeed) {
  const std::string none = islands(2, "none", "--seed 5 --migrate-every 0");
  const std::string ring = islands(2, "ring", "--seed 5 --migrate-every 2min");
  EXPECT_NE(hash_of(none, "islands hash"), hash_of(ring, "islands hash")) << "migration changed nothing";
  // Island 1 (seed 6) without migration is `symb evolve --seed 6`, bit for bit.
  ASSERT_EQ(sh(std::string(SYMB_BINARY) + " evolve " + SYMB_SCENARIO_DIR +
                   "/evolve_maze.yaml --seed 6 --duration 10min --checkpoint-every 0 --quiet --out " +
                   (dir_ / "single").string(),
               "single.log"),
            0)
      << last_output_;
  const std::string single = read_whole_file(dir_ / "single" / "summary.txt");
  const std::string island = read_whole_file(dir_ / "none" / "island_1" / "summary.txt");
  ASSERT_FALSE(hash_of(single, "history hash").empty()) << single;
  EXPECT_EQ(hash_of(single, "history hash"), hash_of(island, "history hash"));
}

TEST_F(IslandsTest, TheLocalJobArrayRunsEachSeedAsSymbEvolveAndCollectMergesThem) {
  const std::string script = std::string(SYMB_SCENARIO_DIR) + "/../scripts/evolve_array";
  ASSERT_EQ(sh("SYMB=" + std::string(SYMB_BINARY) + " " + script + " --array 3-4 --jobs 2 " + SYMB_SCENARIO_DIR +
                   "/evolve_maze.yaml " + (dir_ / "runs").string() + " --duration 5min --checkpoint-every 0",
               "array.log"),
            0)
      << last_output_;
  ASSERT_EQ(sh(std::string(SYMB_BINARY) + " evolve " + SYMB_SCENARIO_DIR +
                   "/evolve_maze.yaml --seed 4 --duration 5min --checkpoint-every 0 --quiet --out " +
                   (dir_ / "direct").string(),
               "direct.log"),
            0);
  EXPECT_EQ(hash_of(read_whole_file(dir_ / "runs" / "seed_4" / "summary.txt"), "history hash"),
            hash_of(read_whole_file(dir_ / "direct" / "summary.txt"), "history hash"));
  ASSERT_EQ(sh(std::string(SYMB_BINARY) + " evolve --collect " + (dir_ / "runs").string() + " " +
                   (dir_ / "direct").string() + " --out " + (dir_ / "report").string(),
               "collect.log"),
            0)
      << last_output_;
  const std::string report = read_whole_file(dir_ / "report" / "collected.txt");
  EXPECT_NE(report.find("collected 3 runs"), std::string::npos) << report;
  EXPECT_NE(report.find("champion fitness over time across runs"), std::string::npos) << report;
  EXPECT_TRUE(fs::exists(dir_ / "report" / "fitness.svg"));
  EXPECT_TRUE(fs::exists(dir_ / "report" / "best.genome"));
  // A folder that is no run is refused with its name.
  EXPECT_NE(sh(std::string(SYMB_BINARY) + " evolve --collect " + dir_.string() + "/nothing", "bad.log"), 0);
  EXPECT_NE(last_output_.find("nothing: no such folder"), std::string::npos) << last_output_;
  // A run whose fitness.csv was damaged is refused with the file and the line.
  const fs::path damaged = dir_ / "damaged";
  fs::create_directories(damaged);
  std::ofstream(damaged / "summary.txt") << "seed: 9\nchampion fitness: 0.5\n";
  std::ofstream(damaged / "fitness.csv") << "time_s,kind,fitness,champion\n60,0,0.1,0.1\n120,0,oops\n";
  EXPECT_NE(
      sh(std::string(SYMB_BINARY) + " evolve --collect " + damaged.string() + " --out " + (dir_ / "report2").string(),
         "damaged.log"),
      0);
  EXPECT_NE(last_output_.find("fitness.csv:3: not a row of four numbers"), std::string::npos) << last_output_;
}

}  // namespace
