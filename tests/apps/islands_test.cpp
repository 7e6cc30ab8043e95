// `symb evolve --islands` under mpirun (an island per rank, champions migrating along a ring) and
// the job array's local fallback (scripts/evolve_array) merged by `symb evolve --collect`. Release
// build only: MPI's processes and the array's are many programs, not threads of ours.
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>

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
  // `symb evolve` of the maze under mpirun, as root too (the box's CI runs as root).
  std::string islands(int ranks, const std::string& out, const std::string& extra) {
    const std::string command =
        "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 mpirun --oversubscribe --mca btl self,vader "
        "--mca oob_tcp_if_include lo -np " +
        std::to_string(ranks) + " " + SYMB_BINARY + " evolve " + SYMB_SCENARIO_DIR +
        "/evolve_maze.yaml --islands --duration 10min --checkpoint-every 0 --quiet --out " + (dir_ / out).string() +
        " " + extra;
    EXPECT_EQ(sh(command, out + ".log"), 0) << last_output_;
    return read_whole_file(dir_ / out / "islands.txt");
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
