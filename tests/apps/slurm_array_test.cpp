// Slurm tried for real: a one-node cluster started by hand in a temporary folder
// (tests/apps/slurm_one_node.sh: its own munged, key and socket, its own slurm.conf with
// proctrack/linuxproc, task/none, loopback, its own ports and state folders), then
// `sbatch --array=1-3 scripts/evolve_array SCENARIO OUT --duration 5min` and
// `symb evolve --collect OUT`, whose report must be the local fallback's
// (`scripts/evolve_array --array 1-3 ...`) for the same seeds; and an island job
// (`sbatch -n 2 --wrap "srun --mpi=pmix symb evolve ... --islands"`), whose islands must be
// mpirun's here. Release build, as root, with Debian's slurmd, slurmctld, slurm-client and munge
// (scripts/setup); skipped with the reason otherwise. The daemons it started are stopped, always
// (TearDown).
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <regex>
#include <string>

#include <gtest/gtest.h>

#include "support/symb_child.hpp"

namespace {

namespace fs = std::filesystem;
using symb::test_support::read_whole_file;

const std::string kSource = std::string(SYMB_SCENARIO_DIR) + "/..";

class SlurmArrayTest : public ::testing::Test {
 protected:
  void SetUp() override {
#ifdef SYMB_SANITIZER
    GTEST_SKIP() << "Slurm: release build only";
#endif
    if (::geteuid() != 0) GTEST_SKIP() << "not root: the hand-started slurmd and munged need root";
    for (const char* tool : {"slurmctld", "slurmd", "sbatch", "srun", "squeue", "scontrol", "munged"})
      if (std::system(("PATH=$PATH:/usr/sbin command -v " + std::string(tool) + " > /dev/null 2>&1").c_str()) != 0)
        GTEST_SKIP() << "no " << tool << " (Debian slurmd, slurmctld, slurm-client, munge: scripts/setup)";
    dir_ = fs::temp_directory_path() / ("slurm_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    cluster_ = dir_ / "cluster";
  }
  void TearDown() override {
    if (dir_.empty()) return;
    sh(kSource + "/tests/apps/slurm_one_node.sh stop " + cluster_.string(), "stop.log");
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  // A shell command line (no single quotes in it), its output into `log`; its exit status.
  int sh(const std::string& command, const std::string& log) {
    symb::test_support::SymbChild child("/bin/sh", "-c 'PATH=$PATH:/usr/sbin; " + command + "'", dir_ / log);
    const int status = child.wait();
    last_output_ = child.output();
    return status;
  }
  // collected.txt with the runs' parent folder put as OUT: the same for both arrays.
  std::string report(const std::string& name, const fs::path& runs) {
    EXPECT_EQ(
        sh(std::string(SYMB_BINARY) + " evolve --collect " + runs.string() + " --quiet --out " + (dir_ / name).string(),
           name + ".log"),
        0)
        << last_output_;
    const std::string text = read_whole_file(dir_ / name / "collected.txt");
    return std::regex_replace(text, std::regex(runs.string()), "OUT");
  }
  fs::path dir_, cluster_;
  std::string last_output_;
};

TEST_F(SlurmArrayTest, ArrayAndIslandJobsOnAOneNodeClusterGiveWhatTheyGiveHere) {
  ASSERT_EQ(sh(kSource + "/tests/apps/slurm_one_node.sh start " + cluster_.string(), "start.log"), 0) << last_output_;
  const std::string slurm = "SLURM_CONF=" + (cluster_ / "slurm.conf").string() + " ";
  const std::string arguments = std::string(SYMB_SCENARIO_DIR) + "/evolve_maze.yaml ";
  const std::string extra = " --duration 5min --checkpoint-every 0";
  ASSERT_EQ(
      sh(slurm + "SYMB=" + SYMB_BINARY + " sbatch --parsable --array=1-3 --output=" + dir_.string() +
             "/job_%A_%a.out " + kSource + "/scripts/evolve_array " + arguments + (dir_ / "slurm").string() + extra,
         "sbatch.log"),
      0)
      << last_output_;
  std::smatch id;
  ASSERT_TRUE(std::regex_search(last_output_, id, std::regex(R"((\d+))"))) << last_output_;
  const std::string job = id[1];
  // An island job: two ranks started by srun through Slurm's PMIx (Debian's OpenMPI has no PMI-1/2).
  const std::string island_args = std::string(SYMB_BINARY) + " evolve " + arguments +
                                  "--islands --seed 5 --duration 10min --migrate-every 2min --checkpoint-every 0 "
                                  "--quiet --out ";
  ASSERT_EQ(sh(slurm + "sbatch --parsable -n 2 --output=" + dir_.string() +
                   "/islands_%j.out --wrap=\"srun --mpi=pmix " + island_args + (dir_ / "islands_slurm").string() + "\"",
               "sbatch_islands.log"),
            0)
      << last_output_;
  ASSERT_TRUE(std::regex_search(last_output_, id, std::regex(R"((\d+))"))) << last_output_;
  const std::string island_job = id[1];
  // Done when the queue no longer holds them (a minute at most); every task completed with 0. Only
  // an squeue that answered counts: one cut short by its timeout (a busy box) prints nothing too.
  ASSERT_EQ(sh("for i in $(seq 240); do out=$(" + slurm + "timeout 5 squeue -h -j " + job + "," + island_job +
                   ") && [ -z \"$out\" ] && exit 0; sleep 0.25; done; exit 1",
               "squeue.log"),
            0)
      << "the jobs did not finish within a minute: " << read_whole_file(cluster_ / "log" / "slurmctld.log");
  ASSERT_EQ(sh(slurm + "scontrol -o show job " + job, "scontrol.log"), 0) << last_output_;
  const std::string tasks = last_output_;
  const std::regex completed(R"(ArrayTaskId=\d+ .*JobState=COMPLETED .*ExitCode=0:0)");
  EXPECT_EQ(std::distance(std::sregex_iterator(tasks.begin(), tasks.end(), completed), std::sregex_iterator()), 3)
      << tasks;
  for (int seed : {1, 2, 3})
    EXPECT_TRUE(fs::exists(dir_ / "slurm" / ("seed_" + std::to_string(seed)) / "summary.txt")) << seed;

  // The local fallback, same seeds, same contract.
  ASSERT_EQ(sh("SYMB=" + std::string(SYMB_BINARY) + " " + kSource + "/scripts/evolve_array --array 1-3 --jobs 2 " +
                   arguments + (dir_ / "local").string() + extra,
               "local.log"),
            0)
      << last_output_;
  const std::string on_slurm = report("report_slurm", dir_ / "slurm");
  const std::string here = report("report_local", dir_ / "local");
  EXPECT_NE(on_slurm.find("collected 3 runs"), std::string::npos) << on_slurm;
  EXPECT_EQ(on_slurm, here);

  // The island job gives what mpirun gives here: the same islands, hash for hash.
  ASSERT_EQ(sh(slurm + "scontrol -o show job " + island_job, "scontrol_islands.log"), 0) << last_output_;
  EXPECT_NE(last_output_.find("JobState=COMPLETED"), std::string::npos)
      << last_output_ << read_whole_file(dir_ / ("islands_" + island_job + ".out"));
  ASSERT_EQ(sh("OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 timeout 60 mpirun --oversubscribe --mca btl "
               "self,vader --mca oob_tcp_if_include lo -np 2 " +
                   island_args + (dir_ / "islands_local").string(),
               "islands_local.log"),
            0)
      << last_output_;
  const auto hash = [](const std::string& text) {
    std::smatch m;
    return std::regex_search(text, m, std::regex("islands hash: ([0-9a-f]{16})")) ? m[1].str() : std::string();
  };
  const std::string slurm_islands = read_whole_file(dir_ / "islands_slurm" / "islands.txt");
  EXPECT_NE(slurm_islands.find("islands: 2 ranks"), std::string::npos) << slurm_islands;
  EXPECT_FALSE(hash(slurm_islands).empty()) << slurm_islands;
  EXPECT_EQ(hash(slurm_islands), hash(read_whole_file(dir_ / "islands_local" / "islands.txt")));
}

}  // namespace
