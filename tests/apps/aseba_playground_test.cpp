// A scenario's robot task graph driving a Thymio II in Aseba Playground (Debian `aseba`), over
// the real robot's protocol on TCP: the world is written by `symb board --playground`'s generator,
// Playground is started headless on a free local port, and the robot's node is built as `symb
// board --robot aseba:tcp:...` builds it (ThymioAseba devices, the scenario's tasks and hooks).
//  - The MDL2e maze controller, and the Braitenberg perceptron, drive for a few seconds without
//    wall contact, judged from the robot's own proximity readings (none at or above the reading
//    of a wall 1 cm from a sensor), and move a stated distance by odometry (the wheel speeds the
//    robot measures; Playground exposes no pose over Aseba). Each starts 45 cm below the maze's
//    top wall, heading for it, so it meets a wall within the run.
//  - Killing Playground mid-run is noticed, reported in the node's log and stops the wheels at
//    once (within two control periods of noticing); a Playground started again on the same port
//    is picked up again and the robot reads its sensors.
// Playground runs in real time: about 7 + 5 s (the sanitizer builds run the first only). Without
// `asebaplayground` the tests are skipped.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <thread>

#include <gtest/gtest.h>

#include "symb/io/tcp_stream.hpp"
#include "symb/kernel/thread_executor.hpp"
#include "symb/robot/thymio_aseba.hpp"
#include "symb/robot/thymio_ir.hpp"
#include "symb/sim/playground_world.hpp"
#include "symb/sim/robot_system.hpp"
#include "symb/sim/scenario.hpp"

#include "support/eventually.hpp"
#include "support/measured.hpp"

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using namespace symb;

std::string find_playground() {
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/bin";
  std::size_t at = 0;
  while (at <= dirs.size()) {
    const std::size_t end = std::min(dirs.find(':', at), dirs.size());
    const fs::path p = fs::path(dirs.substr(at, end - at)) / "asebaplayground";
    if (::access(p.c_str(), X_OK) == 0) return p;
    at = end + 1;
  }
  return {};
}

// Aseba Playground as a child process, headless, its home (where it keeps simulated SD cards) in
// the test's folder.
class Playground {
 public:
  Playground(const std::string& binary, const fs::path& world, const fs::path& dir) {
    std::fflush(stdout);  // a child must not write the test's buffered output again
    pid_ = ::fork();
    if (pid_ == 0) {
      ::setenv("QT_QPA_PLATFORM", "offscreen", 1);
      ::setenv("HOME", dir.c_str(), 1);
      ::setenv("XDG_RUNTIME_DIR", dir.c_str(), 1);
      const std::string log = (dir / "playground.log").string();
      if (std::FILE* f = std::freopen(log.c_str(), "a", stdout)) (void)f;
      ::dup2(::fileno(stdout), 2);
      ::execl(binary.c_str(), "asebaplayground", world.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
  }
  ~Playground() { kill(); }
  void kill() {
    if (pid_ <= 0) return;
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, nullptr, 0);
    pid_ = -1;
  }

 private:
  pid_t pid_ = -1;
};

std::uint16_t free_port() {
  auto l = io::TcpListener::bind("127.0.0.1", 0);
  return l ? (*l)->port() : 0;
}

// Connects (Playground takes a second or two to listen) and checks the node is a Thymio.
std::shared_ptr<robot::thymio::AsebaThymio> connect_thymio(std::uint16_t port, kernel::Duration period) {
  const auto end = std::chrono::steady_clock::now() + 15s;
  std::string last;
  while (std::chrono::steady_clock::now() < end) {
    auto s = io::TcpStream::connect("127.0.0.1", port, 1s);
    if (s) {
      robot::thymio::AsebaThymioOptions o;
      o.control_period = period;
      // Playground is a process of its own on a box the other tests share: a reply a few periods
      // late is a slow simulator, not a lost robot (a killed one closes the connection at once).
      o.reply_timeout = 200ms;
      o.reopen_first = 100ms;
      o.reopen_most = 400ms;
      auto t = robot::thymio::AsebaThymio::create(std::shared_ptr<io::IOStream>(std::move(s).value()), o);
      auto st = t->connect();
      if (st) return t;
      last = st.error();
    } else {
      last = s.error();
    }
    std::this_thread::sleep_for(100ms);
  }
  ADD_FAILURE() << "no Thymio on port " << port << ": " << last;
  return nullptr;
}

// The highest reading each IR sensor gave.
class IrMaximum final : public os::Task {
 public:
  std::array<float, 7> max() const {
    std::lock_guard lock(mu_);
    return max_;
  }

 protected:
  void on_message(const os::Message& m) override {
    std::lock_guard lock(mu_);
    const auto v = m.numbers();
    for (std::size_t i = 0; i < v.size() && i < max_.size(); ++i) max_[i] = std::max(max_[i], v[i]);
  }

 private:
  mutable std::mutex mu_;
  std::array<float, 7> max_{};
};

struct PlaygroundRun {
  std::shared_ptr<robot::thymio::AsebaThymio> thymio;
  std::unique_ptr<kernel::ThreadExecutor> executor;
  std::unique_ptr<sim::RobotSystem> system;
  IrMaximum* ir_max = nullptr;
};

class AsebaPlayground : public ::testing::Test {
 protected:
  void SetUp() override {
    binary_ = find_playground();
    if (binary_.empty())
      GTEST_SKIP() << "asebaplayground is not installed (Debian package aseba, scripts/setup installs it)";
    dir_ = fs::temp_directory_path() / ("symb_aseba_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (run_.system) run_.thymio->stop();
    run_.system.reset();
    run_.thymio.reset();
    playground_.reset();
    if (!dir_.empty() && !HasFailure()) fs::remove_all(dir_);
  }

  // Loads the scenario, puts its robot `below_top` cm under the top wall heading for it, writes
  // the world, starts Playground and builds the robot's node on its Thymio.
  void start(const std::string& scenario_file, double below_top) {
    auto loaded = sim::load_scenario(std::string(SYMB_SCENARIO_DIR) + "/" + scenario_file);
    ASSERT_TRUE(loaded) << loaded.error();
    scenario_ = std::move(loaded).value();
    sim::RobotSpec& robot = scenario_.robots.front();
    robot.start.y = scenario_.world.height - below_top;
    port_ = free_port();
    ASSERT_NE(port_, 0);
    auto world = sim::playground_world(scenario_, port_);
    ASSERT_TRUE(world) << world.error();
    world_ = dir_ / "world.playground";
    std::ofstream(world_) << *world;
    playground_ = std::make_unique<Playground>(binary_, world_, dir_);
    run_.thymio = connect_thymio(port_, scenario_.control_period);
    ASSERT_TRUE(run_.thymio);
    run_.thymio->on_report([this](os::LogLevel, std::string_view text) {
      std::lock_guard lock(reports_mu_);
      reports_.emplace_back(text);
    });
    run_.executor = std::make_unique<kernel::ThreadExecutor>();
    sim::RobotSystemOptions ro;
    ro.control_period = scenario_.control_period;
    ro.read_program = sim::file_program_reader(scenario_.base_dir);
    sim::RobotDevices devices;
    devices.ir = run_.thymio->ir();
    devices.wheels = run_.thymio->wheels();
    devices.ground = run_.thymio->ground();
    auto built = sim::RobotSystem::build(*run_.executor, robot, devices, ro);
    ASSERT_TRUE(built) << built.error();
    run_.system = std::move(built).value();
    os::Node& node = run_.system->node();
    auto watcher = std::make_unique<IrMaximum>();
    run_.ir_max = watcher.get();
    auto id = node.create("ir_max", std::move(watcher), {});
    ASSERT_TRUE(id) << id.error();
    ASSERT_TRUE(node.hook(*node.find("ir"), *id));
    run_.thymio->start();
  }

  void expect_no_contact_and_distance(double measured_cm, double margin_cm) {
    const auto stats = run_.thymio->stats();
    const auto max = run_.ir_max->max();
    const float contact = static_cast<float>(robot::thymio::ir_reading(1.0));
    float highest = 0;
    for (float v : max) highest = std::max(highest, v);
    EXPECT_LT(highest, contact) << "an IR reading of " << highest << " is a wall within 1 cm";
    EXPECT_GT(highest, static_cast<float>(robot::thymio::ir_reading(robot::thymio::kIrRange - 1)))
        << "the robot never came near a wall";
    EXPECT_TRUE(symb::testing::near_measured(stats.path, measured_cm, margin_cm)) << "odometry path, cm";
    EXPECT_EQ(stats.losses, 0u);
    EXPECT_EQ(stats.link.refused(), 0u);
    std::printf("[ measured ] highest IR %.0f (contact %.0f), path %.1f cm, %llu samples\n", highest, contact,
                stats.path, static_cast<unsigned long long>(stats.samples));
  }

  std::string binary_;
  fs::path dir_, world_;
  sim::Scenario scenario_;
  std::uint16_t port_ = 0;
  std::unique_ptr<Playground> playground_;
  PlaygroundRun run_;
  std::mutex reports_mu_;
  std::vector<std::string> reports_;
};

TEST_F(AsebaPlayground, Mdl2eMazeControllerDrivesWithoutContact) {
  ASSERT_NO_FATAL_FAILURE(start("maze.yaml", 45));
  std::this_thread::sleep_for(6s);
  // 300 units forward (9.96 cm/s), turning in place at the wall: measured 51.6 to 52.1 cm in 6 s
  // (highest IR 3797); the margin leaves room for a loaded machine's late readings.
  expect_no_contact_and_distance(52, 8);

  // Link loss: Playground killed mid-run.
  const auto before = run_.thymio->stats();
  ASSERT_TRUE(before.up);
  playground_->kill();
  EXPECT_TRUE(symb::testing::eventually([&] { return run_.thymio->stats().losses > 0; }));
  auto lost = run_.thymio->stats();
  ASSERT_EQ(lost.losses, 1u);
  EXPECT_FALSE(lost.up);
  EXPECT_LE(lost.last_stop_delay, 2 * scenario_.control_period);
  EXPECT_EQ(lost.left_target, 0);
  EXPECT_EQ(lost.right_target, 0);
  // The report follows the count, from the backend's thread.
  ASSERT_TRUE(symb::testing::eventually([&] {
    std::lock_guard lock(reports_mu_);
    return !reports_.empty();
  }));
  {
    std::lock_guard lock(reports_mu_);
    EXPECT_NE(reports_.front().find("lost"), std::string::npos) << reports_.front();
  }
  // The controller's commands go nowhere.
  EXPECT_TRUE(symb::testing::eventually([&] { return run_.thymio->stats().wheel_refused > 0; }));

  // A Playground started again on the same port is picked up again.
  playground_ = std::make_unique<Playground>(binary_, world_, dir_);
  EXPECT_TRUE(symb::testing::eventually([&] { return run_.thymio->stats().reconnects > 0; }));
  auto back = run_.thymio->stats();
  ASSERT_EQ(back.reconnects, 1u);
  EXPECT_TRUE(back.up);
  EXPECT_TRUE(symb::testing::eventually([&] { return run_.thymio->stats().samples > back.samples + 5; }));
  std::string last;
  EXPECT_TRUE(symb::testing::eventually([&] {
    std::lock_guard lock(reports_mu_);
    last = reports_.back();
    return last.find("link back") != std::string::npos;
  })) << last;
}

TEST_F(AsebaPlayground, BraitenbergPerceptronDrivesWithoutContact) {
#ifdef SYMB_SANITIZER
  // Real time cannot be sped up: the sanitizer builds run the maze controller's test only.
  GTEST_SKIP() << "release build only (Playground runs in real time; the MDL2e test covers the sanitizers)";
#endif
  ASSERT_NO_FATAL_FAILURE(start("braitenberg.yaml", 45));
  std::this_thread::sleep_for(5s);
  // Measured 40.7 to 40.8 cm in 5 s (highest IR 3940).
  expect_no_contact_and_distance(41, 8);
}

}  // namespace
