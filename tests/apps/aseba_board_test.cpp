// `symb board`'s Aseba forms without Playground (apps/hil/aseba_board.cpp): a malformed --robot
// is a usage error naming the form, a robot nobody answers for and a node that is not a Thymio
// are failures with the reason, --playground writes the world file, and a board run against a
// fake Thymio (tests/support/aseba_node.hpp) drives its motor targets, answers on its shell line
// and ends with the stop.
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include <gtest/gtest.h>

#include "symb/apps/hil/hil_commands.hpp"
#include "symb/io/pty_pair.hpp"

#include "support/aseba_node.hpp"

namespace symb::apps::hil {
namespace {

namespace fs = std::filesystem;

struct Outcome {
  int status;
  std::string out, err;
};

Outcome board(std::vector<std::string> args) {
  std::vector<std::string_view> views(args.begin(), args.end());
  std::ostringstream out, err;
  CliContext ctx{out, err, false};
  const int status = run_board_command(views, ctx);
  return {status, out.str(), err.str()};
}

const std::string kMaze = std::string(SYMB_SCENARIO_DIR) + "/maze.yaml";

TEST(AsebaBoard, MalformedTargetsAreUsageErrors) {
  for (const char* bad : {"aseba:tcp:localhost", "aseba:tcp:localhost:0", "aseba:udp:x:1", "aseba:serial:"}) {
    const Outcome o = board({kMaze, "--robot", bad});
    EXPECT_EQ(o.status, kExitUsage) << bad << ": " << o.err;
    EXPECT_NE(o.err.find("--robot"), std::string::npos) << o.err;
  }
  auto t = parse_aseba_target("aseba:tcp:[::1]:33333");
  ASSERT_TRUE(std::holds_alternative<AsebaTarget>(t));
  EXPECT_EQ(std::get<AsebaTarget>(t).host, "::1");
  EXPECT_EQ(std::get<AsebaTarget>(t).port, 33333);
}

// A Thymio keeps its own time: only a board the simulator drives can follow its frames.
TEST(AsebaBoard, LockstepIsAUsageErrorWithAThymioOrAPlaygroundFile) {
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{kMaze, "--robot", "aseba:tcp:127.0.0.1:1", "--lockstep"},
        std::vector<std::string>{kMaze, "--playground", "x.playground", "--lockstep"}}) {
    const Outcome o = board(args);
    EXPECT_EQ(o.status, kExitUsage) << o.err;
    EXPECT_NE(o.err.find("--lockstep is for a board the simulator drives"), std::string::npos) << o.err;
  }
}

TEST(AsebaBoard, NobodyThereAndNotAThymioAreFailuresWithTheReason) {
  symb::testing::FakeAsebaNode epuck("e-puck", {{"prox", 8}, {"motor.left.target", 1}});
  ASSERT_TRUE(epuck.listen());
  const Outcome o = board({kMaze, "--robot", "aseba:tcp:127.0.0.1:" + std::to_string(epuck.port())});
  EXPECT_EQ(o.status, kExitFailure);
  EXPECT_NE(o.err.find("'e-puck' is not a Thymio II: no prox.horizontal (7 words), no motor.right.target (1 word)"),
            std::string::npos)
      << o.err;
  const std::uint16_t port = epuck.port();
  epuck.close();
  const Outcome none = board({kMaze, "--robot", "aseba:tcp:127.0.0.1:" + std::to_string(port)});
  EXPECT_EQ(none.status, kExitFailure);
  EXPECT_NE(none.err.find("cannot connect"), std::string::npos) << none.err;
}

TEST(AsebaBoard, PlaygroundWritesTheWorldFile) {
  const fs::path out = fs::temp_directory_path() / ("symb_playground_" + std::to_string(::getpid()) + ".playground");
  const Outcome o = board({kMaze, "--playground", out.string(), "--port", "34000"});
  ASSERT_EQ(o.status, kExitOk) << o.err;
  std::ifstream in(out);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_NE(text.str().find("port=\"34000\""), std::string::npos) << text.str();
  EXPECT_NE(o.out.find("asebaplayground"), std::string::npos) << o.out;
  fs::remove(out);
}

TEST(AsebaBoard, RunsTheScenarioOnAFakeThymioWithItsShell) {
  symb::testing::FakeAsebaNode thymio;
  ASSERT_TRUE(thymio.listen());
  const std::uint16_t prox = thymio.address_of("prox.horizontal");
  thymio.poke(prox + 2, 3000);  // a wall ahead: the maze controller turns
  auto pty = io::PtyPair::open("shell");
  ASSERT_TRUE(pty) << pty.error();
  Outcome o;
  std::thread run([&] {
    o = board({kMaze, "--robot", "aseba:tcp:127.0.0.1:" + std::to_string(thymio.port()), "--duration", "3s", "--quiet",
               "--shell", pty->slave_path});
  });
  // The shell answers on its line as on any board. The question is asked again until the board
  // has opened its line (bytes written before that may be flushed by its opening), for most of
  // the run: a board slow to start on a busy box (a sanitizer build) has time to.
  std::string replies;
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(2800);
  auto next_ask = std::chrono::steady_clock::now() + std::chrono::milliseconds(200);
  int asked = 0;
  while (std::chrono::steady_clock::now() < end && replies.find("controller") == std::string::npos) {
    if (std::chrono::steady_clock::now() >= next_ask) {
      asked += pty->master->write_all(io::as_bytes("tasks\n")) ? 1 : 0;
      next_ask += std::chrono::milliseconds(200);
    }
    std::byte buf[512];
    auto n = pty->master->read_some(buf, std::chrono::milliseconds(20));
    if (n) replies.append(reinterpret_cast<const char*>(buf), *n);
  }
  run.join();
  EXPECT_GT(asked, 0) << replies;
  EXPECT_NE(replies.find("controller"), std::string::npos) << replies;
  EXPECT_NE(replies.find("wheels"), std::string::npos) << replies;
  EXPECT_EQ(o.status, kExitOk) << o.err;
  EXPECT_NE(o.out.find("on Aseba node 1 'thymio-II'"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("losses=0"), std::string::npos) << o.out;
  EXPECT_GE(thymio.sets(), 3u);  // zero at connect, the controller's commands, zero at the end
  EXPECT_EQ(thymio.peek(thymio.address_of("motor.left.target")), 0);
  EXPECT_EQ(thymio.peek(thymio.address_of("motor.right.target")), 0);
}

}  // namespace
}  // namespace symb::apps::hil
