// A world split over processes (issue 19; docs/bus.md "A world split over processes"): `symb run
// SCENARIO --bus dds --remote NAMES` runs the world and the other robots, `symb serve --scenario
// SCENARIO --robot NAME` one remote robot's node each, in lockstep over Cyclone DDS. The split run
// must be the in-process run: the same trajectory hash, the world's radio carried too. A robot process killed mid-run
// is reported by the world, which stops its wheels and finishes the run; garbage from a foreign peer is counted and
// dropped on both sides; bad input gets a clear error. Each test uses its own DDS topic prefix (from the pid) on its
// own domain. Release build only, as serve_test.cpp: DDS's threads are checked under the sanitizers by
// tests/io/dds_bus_test.cpp.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "symb/io/dds/dds_frame_stream.hpp"
#include "symb/io/frame_codec.hpp"
#include "symb/io/stream_task.hpp"

#include "support/symb_child.hpp"

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using symb::test_support::SymbChild;

const std::string kSwarm = std::string(SYMB_SCENARIO_DIR) + "/swarm.yaml";
const std::string kMedea = std::string(SYMB_SCENARIO_DIR) + "/medea_swarm.yaml";

class SplitWorld : public ::testing::Test {
 protected:
  void SetUp() override {
#ifdef SYMB_SANITIZER
    GTEST_SKIP() << "processes over DDS: release build only";
#endif
    tag_ = std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()).substr(0, 12) + "_" +
           std::to_string(::getpid());
    dir_ = fs::temp_directory_path() / ("split_" + tag_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::uint32_t domain() const { return 10 + static_cast<std::uint32_t>(::getpid() % 200); }
  // The options that put a world and its robots on this test's topics, with `lease_`.
  std::string bus() const {
    return " --domain " + std::to_string(domain()) + " --prefix split_" + tag_ + " --lease " +
           std::to_string(lease_.count()) + "ms";
  }
  std::unique_ptr<SymbChild> robot(const std::string& name, const std::string& more = "",
                                   const std::string& scenario = kSwarm) {
    return std::make_unique<SymbChild>(SYMB_BINARY, "serve --scenario " + scenario + " --robot " + name + bus() + more,
                                       dir_ / ("robot_" + name + ".txt"));
  }
  std::unique_ptr<SymbChild> world(const std::string& remote, const std::string& more,
                                   const std::string& scenario = kSwarm) {
    return std::make_unique<SymbChild>(
        SYMB_BINARY,
        "run " + scenario + " --bus dds --remote " + remote + bus() + " --out " + (dir_ / "split").string() + more,
        dir_ / "world.txt");
  }
  // `symb run` of the same scenario in one process.
  std::string in_process_hash(const std::string& duration, const std::string& scenario = kSwarm) {
    SymbChild one(
        SYMB_BINARY,
        "run " + scenario + " --duration " + duration + " --print-hash --quiet --out " + (dir_ / "one").string(),
        dir_ / "one.txt");
    EXPECT_EQ(one.wait(), 0) << one.output();
    return hash_in(one.output());
  }
  static std::string hash_in(const std::string& text) {
    std::smatch m;
    static const std::regex h("trajectory-hash: ([0-9a-f]{16})");
    return std::regex_search(text, m, h) ? m[1].str() : std::string("none");
  }
  std::string summary() const { return symb::test_support::read_whole_file(dir_ / "split" / "summary.txt"); }
  static void wait_for(const SymbChild& c, const std::string& text, std::chrono::seconds limit = 20s) {
    const auto until = std::chrono::steady_clock::now() + limit;
    while (c.output().find(text) == std::string::npos && std::chrono::steady_clock::now() < until)
      std::this_thread::sleep_for(5ms);
  }

  // Long enough that no process on a busy box goes quiet for that long; a test that kills one
  // makes it short, to see the death soon.
  std::chrono::milliseconds lease_{2000};
  std::string tag_;
  fs::path dir_;
};

TEST_F(SplitWorld, ThreeRobotProcessesRunTheSwarmExactlyAsOneProcess) {
  const std::string one = in_process_hash("5s");
  std::vector<std::unique_ptr<SymbChild>> robots;
  for (const char* name : {"thymio2", "thymio5", "thymio9"}) robots.push_back(robot(name));
  auto w = world("thymio2,thymio5,thymio9", " --duration 5s --print-hash --quiet");
  ASSERT_EQ(w->wait(), 0) << w->output();
  for (auto& r : robots) {
    EXPECT_EQ(r->wait(), 0) << r->output();
    EXPECT_NE(r->output().find("the world ended the run"), std::string::npos) << r->output();
    EXPECT_TRUE(std::regex_search(r->output(),
                                  std::regex("serve-stats: frames=166 missed=0 out_of_order=0 hellos=\\d+ bad=0 ")))
        << r->output();
  }
  const std::string split = hash_in(w->output());
  std::printf("in process %s, split over 4 processes %s\n", one.c_str(), split.c_str());
  EXPECT_EQ(split, one) << "the split run must be the in-process run, bit for bit";
  const std::string s = summary();
  EXPECT_NE(s.find("remote robots: 3 in other processes, lockstep, 0 gone"), std::string::npos) << s;
  // Every step applied its answer (the hello may go out more than once while DDS discovers).
  for (const char* name : {"thymio2", "thymio5", "thymio9"})
    EXPECT_TRUE(
        std::regex_search(s, std::regex(std::string("remote robot ") + name +
                                        ": sent \\d+ \\(0 not taken\\), received \\d+ good, 0 bad; applied 166,")))
        << s;
}

// mEDEA over the world's radio (scenarios/medea_swarm.yaml, a 12 s lifetime): 13 s, so every
// robot has picked its next genome among those it heard and the trajectories depend on what the
// radio carried between the world and the two robot processes.
TEST_F(SplitWorld, TwoRobotProcessesRunTheRadioSwarmExactlyAsOneProcess) {
  const std::string one = in_process_hash("13s", kMedea);
  std::vector<std::unique_ptr<SymbChild>> robots;
  for (const char* name : {"thymio4", "thymio13"}) robots.push_back(robot(name, "", kMedea));
  auto w = world("thymio4,thymio13", " --duration 13s --print-hash --quiet", kMedea);
  ASSERT_EQ(w->wait(), 0) << w->output();
  for (auto& r : robots) {
    EXPECT_EQ(r->wait(), 0) << r->output();
    const std::string out = r->output();
    std::smatch m;
    ASSERT_TRUE(std::regex_search(out, m,
                                  std::regex("serve-stats: frames=433 missed=0 out_of_order=0 hellos=\\d+ bad=0 .* "
                                             "radio_in=(\\d+) radio_dropped=0 radio_stale=0 radio_out=(\\d+)")))
        << r->output();
    std::printf("robot process: %s radio messages in, %s out\n", m[1].str().c_str(), m[2].str().c_str());
    EXPECT_GT(std::stoi(m[2]), 10) << "its genome went on air every 300 ms";
  }
  const std::string split = hash_in(w->output());
  std::printf("in process %s, split over 3 processes %s\n", one.c_str(), split.c_str());
  EXPECT_EQ(split, one) << "the split radio swarm must be the in-process run, bit for bit";
  const std::string s = summary();
  for (const char* name : {"thymio4", "thymio13"})
    EXPECT_TRUE(std::regex_search(s, std::regex(std::string("remote robot ") + name +
                                                ": sent \\d+ \\(0 not taken\\), received \\d+ good, 0 bad; "
                                                "applied 433, 0 stale; waited \\d+ ms; radio: \\d+ messages to it, "
                                                "[1-9]\\d* from it")))
        << s;
}

TEST_F(SplitWorld, AKilledRobotProcessIsReportedItsWheelsStopAndTheRunGoesOn) {
  lease_ = std::chrono::milliseconds(300);
  auto a = robot("thymio1");
  auto b = robot("thymio4");
  // Paced to the wall clock, so the run is under way when a robot dies.
  auto w = world("thymio1,thymio4", " --duration 2s --speed 1 --quiet");
  wait_for(*w, "robot thymio4: its process answered");
  std::this_thread::sleep_for(600ms);
  b->interrupt();  // dies at once: SIGINT's default action, no goodbye on DDS
  EXPECT_EQ(b->wait(), -1);
  EXPECT_EQ(w->wait(), 1) << w->output();  // the run finished, and says a robot was gone
  EXPECT_EQ(a->wait(), 0) << a->output();
  EXPECT_NE(w->output().find("1 remote robot gone during the run"), std::string::npos) << w->output();
  const std::string s = summary();
  EXPECT_NE(s.find("simulated: 1.98 s in 66 steps"), std::string::npos) << s;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(s, m, std::regex("remote robot gone: thymio4 at step (\\d+): (.*)"))) << s;
  const int at = std::stoi(m[1]);
  std::printf("thymio4 gone at step %d: %s\n", at, m[2].str().c_str());
  // Killed about 0.6 s in (step 20): the world waits on the step it sent until the 300 ms lease
  // runs out, so the robot is gone at the step after the last it answered.
  EXPECT_GT(at, 12);
  EXPECT_LT(at, 55);
  EXPECT_NE(m[2].str().find("lost"), std::string::npos) << "noticed by DDS liveliness: " << m[2];
  EXPECT_TRUE(std::regex_search(s, std::regex("remote robot thymio1: sent \\d+ \\(0 not taken\\), received \\d+ good, "
                                              "0 bad; applied 66,")))
      << "the other robot went on to the end: " << s;
  EXPECT_NE(s.find("remote robots: 2 in other processes, lockstep, 1 gone"), std::string::npos) << s;
  // Its wheels stopped from the step after it was gone: steps.csv has it standing to the end.
  std::istringstream csv(symb::test_support::read_whole_file(dir_ / "split" / "steps.csv"));
  int rows = 0, standing = 0;
  for (std::string line; std::getline(csv, line);) {
    if (line.find(",thymio4,") == std::string::npos) continue;
    ++rows;
    if (rows > at + 1) standing += line.ends_with(",0.000,0.000,0") || line.ends_with(",0.000,0.000,1") ? 1 : 0;
  }
  EXPECT_EQ(rows, 66);
  EXPECT_EQ(standing, 66 - at - 1) << "thymio4's wheels at rest after step " << at;
}

// A foreign peer writes on a robot's topics: bytes that are no frame and frames that are no frame
// of the protocol. Both sides count them exactly and drop them; the run is still the in-process one.
TEST_F(SplitWorld, ForeignGarbageIsCountedAndDroppedOnBothSides) {
  const std::string one = in_process_hash("1s");
  auto links = symb::io::DdsFrameLinks::create({domain(), "split_" + tag_, lease_});
  ASSERT_TRUE(links.ok()) << links.error();
  const auto garbage = [](symb::io::DdsFrameStream& s) {
    const std::vector<std::byte> junk{std::byte{0}, std::byte{0x11}, std::byte{0x22}, std::byte{0x33}, std::byte{0}};
    for (int k = 0; k < 3; ++k) ASSERT_TRUE(s.write_all(junk).ok());
    std::vector<std::byte> frame;
    const float two[] = {1, 2};  // a good frame, but no frame of the protocol
    symb::io::encode_frame(symb::io::encode_numbers(two), frame);
    for (int k = 0; k < 2; ++k) ASSERT_TRUE(s.write_all(frame).ok());
    EXPECT_TRUE(s.flush(2s));
  };
  auto r = robot("thymio6");
  {
    // On the robot's input, before the world came: the stream the world would write.
    auto s = (*links)->stream("thymio6", "to_robot", "to_world");
    ASSERT_TRUE(s.ok()) << s.error();
    ASSERT_TRUE((*s)->wait_matched(10s));
    garbage(**s);
  }
  // On the world's input, while it runs: the stream the robot writes, made before the world, so
  // that DDS discovers it with the robot's.
  auto made = (*links)->stream("thymio6", "to_world", "to_robot");
  ASSERT_TRUE(made.ok()) << made.error();
  std::shared_ptr<symb::io::DdsFrameStream> foreign = *made;
  auto w = world("thymio6", " --duration 1s --speed 1 --print-hash --quiet");
  wait_for(*w, "robot thymio6: its process answered");
  ASSERT_TRUE(foreign->wait_matched(5s));
  garbage(*foreign);
  foreign.reset();
  ASSERT_EQ(w->wait(), 0) << w->output();
  EXPECT_EQ(r->wait(), 0) << r->output();
  EXPECT_TRUE(std::regex_search(r->output(),
                                std::regex("frames=33 missed=0 out_of_order=0 hellos=\\d+ bad=5 crc=\\d+ malformed=2")))
      << r->output();
  EXPECT_TRUE(std::regex_search(summary(), std::regex("received \\d+ good, 5 bad; applied 33,"))) << summary();
  EXPECT_EQ(hash_in(w->output()), one) << "garbage dropped, the run is the in-process one";
}

TEST_F(SplitWorld, BadInputGetsAClearError) {
  struct Case {
    std::string args;
    int status;
    std::string says;
  };
  const std::string run = "run " + kSwarm + " --duration 1s --out " + (dir_ / "bad").string();
  const Case cases[] = {
      {run + " --remote thymio1", 2, "--remote needs --bus dds"},
      {run + " --bus udp --remote thymio1", 2, "--bus 'udp': the only bus is dds"},
      {run + " --bus dds", 2, "name them with --remote"},
      {run + " --bus dds --remote thymio1,,thymio2", 2, "--remote 'thymio1,,thymio2': '' cannot name a robot"},
      {run + " --bus dds --remote thymio1,thymio1", 2, "thymio1 twice"},
      {run + " --bus dds --remote thymio1 --domain 300", 2, "--domain"},
      {run + " --lease 1s", 2, "--lease is for --remote"},
      {run + " --bus dds --remote thymio1 --realtime", 2, "not with --realtime"},
      {run + " --bus dds --remote nobody" + bus(), 1, "--remote: " + kSwarm + " has no robot 'nobody'"},
      // A robot whose process never comes.
      {run + " --bus dds --remote thymio1 --remote-wait 300ms" + bus(), 1,
       "no answer from the process of remote robot thymio1 within 300 ms"},
      {"serve --robot thymio1", 2, "--robot needs --scenario FILE"},
      {"serve --scenario " + kSwarm, 2, "--scenario needs --robot NAME"},
      {"serve --scenario " + kSwarm + " --robot thymio1 --exec 'create x y'", 2, "--exec is for --node"},
      {"serve --scenario " + kSwarm + " --robot nobody" + bus(), 1, "no robot named 'nobody' (its robots: thymio0"},
      {"serve --scenario " + kSwarm + " --robot thymio1 --wait 200ms" + bus(), 1, "no world came within 200 ms"},
  };
  for (const Case& c : cases) {
    SymbChild child(SYMB_BINARY, c.args, dir_ / "bad.txt");
    EXPECT_EQ(child.wait(), c.status) << c.args << "\n" << child.output();
    EXPECT_NE(child.output().find(c.says), std::string::npos) << c.args << "\n" << child.output();
  }
}

// Two network namespaces joined by a veth pair, as two machines on one cable: the world in one, a
// robot in the other, found by DDS discovery with no configuration. Needs root (ip netns).
TEST_F(SplitWorld, ARobotInAnotherNetworkNamespaceRunsAsInOneProcess) {
  if (::geteuid() != 0) GTEST_SKIP() << "ip netns needs root";
  const std::string t = std::to_string(::getpid() % 100000);
  const std::string a = "symb_wa_" + t, b = "symb_wb_" + t, va = "swa" + t, vb = "swb" + t;
  const bool ok =
      std::system(("(ip netns add " + a + " && ip netns add " + b + " && ip link add " + va + " type veth peer name " +
                   vb + " && ip link set " + va + " netns " + a + " && ip link set " + vb + " netns " + b +
                   " && ip -n " + a + " addr add 10.78.0.1/24 dev " + va + " && ip -n " + b +
                   " addr add 10.78.0.2/24 dev " + vb + " && ip -n " + a + " link set " + va + " up && ip -n " + b +
                   " link set " + vb + " up && ip -n " + a + " link set lo up && ip -n " + b +
                   " link set lo up) > /dev/null 2>&1")
                      .c_str()) == 0;
  struct Cleanup {
    std::string a, b;
    ~Cleanup() {
      (void)std::system(("ip netns del " + a + " > /dev/null 2>&1; ip netns del " + b + " > /dev/null 2>&1").c_str());
    }
  } cleanup{a, b};
  if (!ok) GTEST_SKIP() << "this machine does not allow network namespaces with a veth pair";
  const std::string one = in_process_hash("3s");
  SymbChild r("/usr/sbin/ip",
              "netns exec " + b + " " + SYMB_BINARY + " serve --scenario " + kSwarm + " --robot thymio3" + bus(),
              dir_ / "robot.txt");
  SymbChild w("/usr/sbin/ip",
              "netns exec " + a + " " + SYMB_BINARY + " run " + kSwarm + " --bus dds --remote thymio3" + bus() +
                  " --duration 3s --print-hash --quiet --out " + (dir_ / "split").string(),
              dir_ / "world.txt");
  ASSERT_EQ(w.wait(), 0) << w.output();
  EXPECT_EQ(r.wait(), 0) << r.output();
  EXPECT_EQ(hash_in(w.output()), one) << "across namespaces, the in-process run";
}

}  // namespace
