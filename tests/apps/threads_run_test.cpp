// `symb run --threads N`: a 2D run on the lockstep executor (kernel::LockstepExecutor) writes
// the same files, byte for byte (trajectories, steps.csv, probes.csv, syslog.txt), with 1, 2 and
// 4 worker threads, for the radio swarm whose robots all probe (scenarios/medea_swarm.yaml); a
// one-robot run writes the same on one virtual-time executor as in lockstep; a 3D organism refuses
// threads.
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

// One robot runs on the virtual-time executor itself (scenario_run.cpp); asked for two threads it
// runs on the lockstep executor. Both write the same files: for the maze demo, and for the
// subsumption demo with every task at priority 500, above the world runner's former 100, where a
// task's tick at a step's instant ran before the world's step on one executor and after it in
// lockstep (the trajectories parted).
TEST(ThreadsRun, OneRobotRunsTheSameOnTheVirtualTimeExecutorAsInLockstep) {
  const fs::path base = fs::temp_directory_path() / ("symb_one_robot_run_" + std::to_string(::getpid()));
  fs::remove_all(base);
  fs::create_directories(base);
  std::string above = read_whole(fs::path(SYMB_SCENARIO_DIR) / "subsumption.yaml");
  int raised = 0;
  for (std::size_t at = above.find("\n        type: "); at != std::string::npos;
       at = above.find("\n        type: ", at + 1), ++raised)
    above.insert(above.find('\n', at + 1) + 1, "        priority: 500\n");
  ASSERT_EQ(raised, 3);
  std::ofstream(base / "subsumption_above.yaml") << above;
  for (const fs::path& scenario : {fs::path(SYMB_SCENARIO_DIR) / "maze.yaml", base / "subsumption_above.yaml"}) {
    std::string files[2][3];
    std::uint64_t hashes[2] = {};
    for (unsigned threads : {0u, 2u}) {
      RunOptions o;
      o.scenario_path = scenario.string();
      o.duration = 60s;
      o.threads = threads;
      o.out_dir = base / (scenario.stem().string() + "_" + std::to_string(threads));
      auto r = run_scenario(o);
      ASSERT_TRUE(r.ok()) << r.error();
      EXPECT_EQ(r->lockstep, threads == 2) << scenario;
      EXPECT_EQ(r->threads, threads == 2 ? 2u : 1u);
      EXPECT_EQ(r->steps, 2000u);
      ASSERT_EQ(r->robots.size(), 1u);
      EXPECT_GT(r->robots[0].distance, 1.0) << scenario;  // it drove: the runs have something to differ in
      const int k = threads == 2 ? 1 : 0;
      hashes[k] = r->trajectory_hash;
      files[k][0] = read_whole(*o.out_dir / "steps.csv");
      files[k][1] = read_whole(*o.out_dir / "probes.csv");
      files[k][2] = read_whole(*o.out_dir / "syslog.txt");
      const std::string summary = read_whole(*o.out_dir / "summary.txt");
      EXPECT_EQ(summary.find("executor: virtual time, one executor (a single robot)") != std::string::npos,
                threads == 0)
          << summary;
      EXPECT_EQ(summary.find("robots' nodes:") != std::string::npos, threads == 2) << summary;
    }
    EXPECT_EQ(hashes[0], hashes[1]) << scenario;
    EXPECT_GT(files[0][0].size(), 10000u);
    EXPECT_TRUE(files[0][0] == files[1][0]) << "steps.csv, " << scenario;
    EXPECT_TRUE(files[0][1] == files[1][1]) << "probes.csv, " << scenario;
    EXPECT_TRUE(files[0][2] == files[1][2]) << "syslog.txt, " << scenario;
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
