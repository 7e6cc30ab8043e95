// `symb run --threads N`: a 2D run on the lockstep executor (kernel::LockstepExecutor) writes
// the same files, byte for byte (trajectories, steps.csv, probes.csv, syslog.txt), with 1, 2 and
// 4 worker threads, for the radio swarm whose robots all probe (scenarios/medea_swarm.yaml); a 3D
// organism refuses threads.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "symb/apps/run/scenario_run.hpp"

namespace symb::apps::run {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

std::string read_whole(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(ThreadsRun, SameFilesWithOneTwoAndFourThreads) {
  const fs::path base = fs::temp_directory_path() / ("symb_threads_run_" + std::to_string(::getpid()));
  fs::remove_all(base);
  std::string first_files[3];
  std::uint64_t first_hash = 0;
  for (unsigned threads : {1u, 2u, 4u}) {
    RunOptions o;
    o.scenario_path = std::string(SYMB_SCENARIO_DIR) + "/medea_swarm.yaml";
    o.duration = 6s;
    o.threads = threads;
    o.out_dir = base / std::to_string(threads);
    auto r = run_scenario(o);
    ASSERT_TRUE(r.ok()) << r.error();
    EXPECT_EQ(r->threads, threads);
    EXPECT_EQ(r->steps, 200u);
    const std::string files[3] = {read_whole(*o.out_dir / "steps.csv"), read_whole(*o.out_dir / "probes.csv"),
                                  read_whole(*o.out_dir / "syslog.txt")};
    EXPECT_GT(files[1].size(), 1000u);  // every robot probes: rows from many threads at once
    if (threads == 1) {
      first_hash = r->trajectory_hash;
      for (int i = 0; i < 3; ++i) first_files[i] = files[i];
      continue;
    }
    EXPECT_EQ(r->trajectory_hash, first_hash) << threads << " threads";
    EXPECT_TRUE(files[0] == first_files[0]) << "steps.csv, " << threads << " threads";
    EXPECT_TRUE(files[1] == first_files[1]) << "probes.csv, " << threads << " threads";
    EXPECT_TRUE(files[2] == first_files[2]) << "syslog.txt, " << threads << " threads";
  }
  fs::remove_all(base);
}

TEST(ThreadsRun, AnOrganismRefusesThreads) {
  RunOptions o;
  o.scenario_path = std::string(SYMB_SCENARIO_DIR) + "/caterpillar.yaml";
  o.duration = 100ms;
  o.threads = 2;
  auto r = run_scenario(o);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().find("--threads: a 3D organism runs on one thread"), std::string::npos) << r.error();
  o.threads = 1;
  EXPECT_TRUE(run_scenario(o).ok());
}

}  // namespace
}  // namespace symb::apps::run
