// The 2D board on the simulator's frames (HilRobotBoard, `symb board --lockstep`): in lockstep
// with the simulator it is the in-process run bit for bit, however long either side is kept off
// its core; bad frames, lost ones, repeats and a new run are counted exactly and answered.
#include "symb/sim/hil_robot_board.hpp"

#include <atomic>
#include <chrono>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "symb/io/frame_codec.hpp"
#include "symb/io/loopback_stream.hpp"
#include "symb/io/stream_task.hpp"
#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/sim/hil_protocol.hpp"
#include "symb/sim/hil_simulator.hpp"
#include "symb/sim/robot_system.hpp"
#include "symb/sim/scenario.hpp"
#include "symb/sim/scenario_session.hpp"
#include "symb/sim/world_factory.hpp"

#include "support/eventually.hpp"

namespace {

using namespace symb;
using namespace symb::sim;
using namespace std::chrono_literals;

Scenario maze() {
  auto sc = load_scenario(std::string(SYMB_SCENARIO_DIR) + "/maze.yaml");
  EXPECT_TRUE(sc.ok()) << sc.error();
  return sc.ok() ? std::move(sc).value() : Scenario{};
}

// Where the robot is after each step, and the wheel speeds it used.
using Trace = std::vector<RobotState>;

void record(Trace& trace, const StepRecord& r) { trace.push_back(r.robots.at(0).state); }

Trace in_process(const Scenario& sc, std::uint64_t steps) {
  kernel::VirtualTimeExecutor ex;
  auto made = ScenarioSession::create(sc, ex);
  EXPECT_TRUE(made.ok()) << made.error();
  Trace trace;
  if (!made.ok()) return trace;
  ScenarioSession& session = **made;
  session.runner().add_observer([&](const StepRecord& r) { record(trace, r); });
  session.start();
  ex.run_until(sc.control_period * static_cast<std::int64_t>(steps));
  return trace;
}

// The scenario's first robot on a HilRobotBoard served on its own thread; `pause()` is called
// before each serve, to keep the board off its core.
class FrameBoard {
 public:
  FrameBoard(const Scenario& sc, std::shared_ptr<io::IOStream> port, FrameClockBoardOptions bo,
             std::function<void()> pause = {}) {
    bo.control_period = sc.control_period;
    board_ = std::make_unique<HilRobotBoard>(ex_, std::move(port), std::move(bo));
    RobotSystemOptions ro;
    ro.control_period = sc.control_period;
    ro.seed = robot_node_seed(sc.seed, 0);
    ro.read_program = file_program_reader(sc.base_dir);
    auto built = RobotSystem::build(ex_, sc.robots.at(0), board_->devices(), std::move(ro));
    EXPECT_TRUE(built.ok()) << built.error();
    if (!built.ok()) return;
    system_ = std::move(built).value();
    EXPECT_TRUE(board_->start().ok());
    thread_ = std::thread([this, pause = std::move(pause)] {
      while (!stop_.load()) {
        if (pause) pause();
        if (!board_->serve(5ms).ok()) break;  // the simulator's end closed
      }
    });
  }
  ~FrameBoard() { join(); }
  void join() {
    stop_.store(true);
    if (thread_.joinable()) thread_.join();
  }
  HilRobotBoard& board() { return *board_; }

 private:
  kernel::VirtualTimeExecutor ex_;
  std::unique_ptr<HilRobotBoard> board_;
  std::unique_ptr<RobotSystem> system_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// Sleeps 40 to 80 ms (over the wheels' 45 ms watchdog) on one call in `one_in`.
std::function<void()> starve(std::uint64_t seed, int one_in) {
  auto random = std::make_shared<kernel::RandomStream>(seed, 7);
  return [random, one_in] {
    if (random->uniform() * one_in < 1.0)
      std::this_thread::sleep_for(std::chrono::milliseconds(40 + static_cast<int>(random->below(41))));
  };
}

// A board on the wall clock could act between a frame and its answer when starved (its
// controller's tick, the wheels' watchdog: docs/hil.md); this one's node only moves with the
// frames. Both sides are kept off their cores at random, longer than the watchdog's 1.5 periods.
TEST(HilRobotBoard, InLockstepABoardAndASimulatorKeptOffTheirCoresAreTheInProcessRunBitForBit) {
  const Scenario sc = maze();
  ASSERT_EQ(sc.robots.size(), 1u);
  constexpr std::uint64_t kSteps = 300;  // 9 s of the maze
  const Trace reference = in_process(sc, kSteps);
  ASSERT_EQ(reference.size(), kSteps);

  auto [a, b] = io::make_loopback_pair("hil2");
  std::shared_ptr<io::IOStream> sim_end = std::move(a), board_end = std::move(b);
  FrameBoard board(sc, board_end, {}, starve(11, 20));
  auto world = make_world(sc.world, sc.seed, 1);
  world->add_robot(sc.robots[0].name, sc.robots[0].kind, sc.robots[0].start);
  HilSimulatorOptions so;
  so.period = sc.control_period;
  so.lockstep = true;
  so.answer_wait = 20s;  // only a silent board waits it out
  HilSimulator simulator(*world, {sim_end}, so);
  Trace hil;
  const auto pause = starve(12, 20);
  simulator.add_observer([&](const StepRecord& r) {
    record(hil, r);
    pause();  // the simulator starved right after an answer
  });
  ASSERT_TRUE(simulator.wait_for_boards(20s).ok());
  auto steps = simulator.run_for(sc.control_period * static_cast<std::int64_t>(kSteps));
  ASSERT_TRUE(steps.ok()) << steps.error();
  // Nobody waits for the last frame's answer, and the board counts a frame after answering it:
  // the line is closed once the board has counted them all.
  EXPECT_TRUE(symb::testing::eventually([&] { return board.board().stats().frames >= kSteps; }));
  sim_end->close();
  board.join();

  ASSERT_EQ(hil.size(), kSteps);
  std::uint64_t moved = 0;
  for (std::uint64_t k = 0; k < kSteps; ++k) {
    const RobotState &x = reference[k], &y = hil[k];
    ASSERT_TRUE(x.pose.x == y.pose.x && x.pose.y == y.pose.y && x.pose.theta == y.pose.theta &&
                x.left_speed == y.left_speed && x.right_speed == y.right_speed)
        << "step " << k + 1 << ": in process (" << x.pose.x << ", " << x.pose.y << ", " << x.left_speed << "), HIL ("
        << y.pose.x << ", " << y.pose.y << ", " << y.left_speed << ")";
    moved += (x.left_speed != 0 || x.right_speed != 0) ? 1 : 0;
  }
  EXPECT_GT(moved, kSteps / 2) << "the robot should drive";
  const auto s = simulator.stats()[0];
  EXPECT_EQ(s.applied, kSteps - 1);  // every step after the first, on its own answer
  EXPECT_EQ(s.late, 0u);
  const auto bs = board.board().stats();
  EXPECT_EQ(bs.frames, kSteps);
  EXPECT_GE(bs.handshakes, 1u);  // sent again each second until answered
  EXPECT_EQ(bs.missed, 0u);
  // Every frame answered; the last answer may find the simulator's end closed already.
  EXPECT_EQ(bs.answers + bs.write_errors, kSteps + bs.handshakes);
  EXPECT_GE(bs.answers, kSteps);
}

// What a simulator end sees: the board's answers, decoded.
std::vector<HilWheelFrame> answers(io::IOStream& end, std::size_t want) {
  std::vector<HilWheelFrame> out;
  io::FrameDecoder decoder;
  std::vector<std::byte> buf(4096);
  for (int i = 0; i < 400 && out.size() < want; ++i) {
    auto got = end.read_some(buf, 10ms);
    if (!got.ok()) break;
    decoder.feed(std::span<const std::byte>(buf.data(), *got), [&](std::span<const std::byte> p) {
      auto w = decode_wheel_payload(p);
      EXPECT_TRUE(w.ok()) << w.error();
      if (w.ok()) out.push_back(*w);
    });
  }
  return out;
}

void send_ir(io::IOStream& end, std::uint32_t seq) {
  HilIrFrame f;
  f.seq = seq;
  ASSERT_TRUE(end.write_all(io::encode_frame(encode_ir_payload(f))).ok());
}

// The maze's robot on a board served on the test's thread, fed by hand through `sim`.
struct HandFed {
  Scenario sc = maze();
  std::shared_ptr<io::IOStream> sim, board_end;
  std::vector<std::string> events;
  kernel::VirtualTimeExecutor ex;
  std::unique_ptr<HilRobotBoard> board;
  std::unique_ptr<RobotSystem> system;

  explicit HandFed(FrameClockBoardOptions bo) {
    auto [a, b] = io::make_loopback_pair("hil2-hand");
    sim = std::move(a);
    board_end = std::move(b);
    bo.control_period = sc.control_period;
    bo.on_event = [this](const std::string& e) { events.push_back(e); };
    board = std::make_unique<HilRobotBoard>(ex, board_end, bo);
    RobotSystemOptions ro;
    ro.control_period = sc.control_period;
    ro.read_program = file_program_reader(sc.base_dir);
    auto built = RobotSystem::build(ex, sc.robots.at(0), board->devices(), std::move(ro));
    EXPECT_TRUE(built.ok()) << built.error();
    if (built.ok()) system = std::move(built).value();
  }
  // Serves what came; the IR frames handled.
  std::size_t serve() {
    std::size_t handled = 0;
    for (int i = 0; i < 5; ++i) {
      auto got = board->serve(5ms);
      EXPECT_TRUE(got.ok());
      if (got.ok()) handled += *got;
    }
    return handled;
  }
};

TEST(HilRobotBoard, BadLostAndRepeatedFramesAreCountedAndANewRunGoesOnFromTheNodesTime) {
  HandFed h({});
  ASSERT_TRUE(h.system);
  HilRobotBoard& board = *h.board;
  const std::shared_ptr<io::IOStream>& sim_end = h.sim;
  const std::vector<std::string>& events = h.events;
  kernel::VirtualTimeExecutor& ex = h.ex;
  const auto serve_all = [&] { return h.serve(); };
  const kernel::Duration period = h.sc.control_period;
  EXPECT_FALSE(board.serve(1ms).ok()) << "not started";
  ASSERT_TRUE(board.start().ok());

  send_ir(*sim_end, 0);
  send_ir(*sim_end, 1);
  send_ir(*sim_end, 2);
  {  // a corrupted frame: CRC
    auto frame = io::encode_frame(encode_ir_payload(HilIrFrame{3, {}}));
    frame[frame.size() / 2] = frame[frame.size() / 2] == std::byte{1} ? std::byte{2} : std::byte{1};
    ASSERT_TRUE(sim_end->write_all(frame).ok());
  }
  {  // a good frame that is no IR frame: three numbers
    const float v[3] = {4, 1, 2};
    ASSERT_TRUE(sim_end->write_all(io::encode_frame(io::encode_numbers(v))).ok());
  }
  send_ir(*sim_end, 5);  // 3 and 4 never came
  send_ir(*sim_end, 5);  // a repeat
  send_ir(*sim_end, 4);  // and an older one
  EXPECT_EQ(serve_all(), 3u);
  // Frame 5 ran the node up to just before the world's step 6.
  EXPECT_EQ(ex.now(), period * 6 - kernel::Duration{1});
  auto s = board.stats();
  EXPECT_EQ(s.handshakes, 1u);
  EXPECT_EQ(s.frames, 3u);
  EXPECT_EQ(s.decoder.crc_errors, 1u);
  EXPECT_EQ(s.malformed, 1u);
  EXPECT_EQ(s.bad_frames(), 2u);
  EXPECT_EQ(s.missed, 2u);
  EXPECT_EQ(s.out_of_order, 2u);
  EXPECT_EQ(s.last_seq, 5u);
  std::vector<std::uint32_t> seqs;
  for (const HilWheelFrame& w : answers(*sim_end, 4)) seqs.push_back(w.seq);
  EXPECT_EQ(seqs, (std::vector<std::uint32_t>{0, 1, 2, 5}));

  // A new run: its frame k is k periods after the node's last tick (5), never back in time.
  send_ir(*sim_end, 0);
  send_ir(*sim_end, 1);
  send_ir(*sim_end, 2);
  EXPECT_EQ(serve_all(), 2u);
  EXPECT_EQ(ex.now(), period * 8 - kernel::Duration{1});
  s = board.stats();
  EXPECT_EQ(s.restarts, 1u);
  EXPECT_EQ(s.handshakes, 1u);
  EXPECT_EQ(s.frames, 5u);
  EXPECT_EQ(s.missed, 2u);
  EXPECT_EQ(s.last_seq, 2u);
  EXPECT_EQ(s.answers, 7u);
  seqs.clear();
  for (const HilWheelFrame& w : answers(*sim_end, 3)) seqs.push_back(w.seq);
  EXPECT_EQ(seqs, (std::vector<std::uint32_t>{0, 1, 2}));
  ASSERT_FALSE(events.empty());
  EXPECT_NE(events.back().find("the simulator started anew"), std::string::npos) << events.back();

  // Silence past lost_periods, then a frame: lost, then back.
  std::this_thread::sleep_for(period * (board.options().lost_periods + 2));
  auto quiet = board.serve(1ms);
  ASSERT_TRUE(quiet.ok()) << quiet.error();
  EXPECT_EQ(*quiet, 0u);
  EXPECT_NE(events.back().find("link lost: no IR frame for"), std::string::npos) << events.back();
  send_ir(*sim_end, 3);
  EXPECT_EQ(serve_all(), 1u);
  EXPECT_NE(events.back().find("link back after"), std::string::npos) << events.back();
  s = board.stats();
  EXPECT_EQ(s.link_losses, 1u);
  EXPECT_EQ(s.link_recoveries, 1u);

  // The line's end: serve() says so, and nothing was lost before it.
  sim_end->close();
  std::size_t served_ok = 0;
  bool failed = false;
  for (int i = 0; i < 50 && !failed; ++i) {
    auto got = board.serve(5ms);
    failed = !got.ok();
    served_ok += got.ok() ? *got : 0;
  }
  EXPECT_TRUE(failed) << "an ended line is reported";
  EXPECT_EQ(served_ok, 0u);
  EXPECT_EQ(board.stats().frames, 6u);
}

// A frame far ahead of the node (a simulator that went on alone for a long while, or nonsense
// from a peer) moves its clock one period, not all of them: no frame makes the board run more
// than max_catch_up periods, and the run goes on from there.
TEST(HilRobotBoard, AFrameFarAheadMovesTheNodeOnePeriodAndTheRunGoesOn) {
  FrameClockBoardOptions bo;
  bo.max_catch_up = 50;
  HandFed h(bo);
  ASSERT_TRUE(h.system);
  ASSERT_TRUE(h.board->start().ok());
  const std::shared_ptr<io::IOStream>& sim_end = h.sim;
  const std::vector<std::string>& events = h.events;
  kernel::VirtualTimeExecutor& ex = h.ex;
  HilRobotBoard& board = *h.board;
  const auto serve = [&] { return h.serve(); };
  const kernel::Duration period = h.sc.control_period;
  send_ir(*sim_end, 0);
  send_ir(*sim_end, 1);
  send_ir(*sim_end, 51);  // 50 periods on: caught up with
  EXPECT_EQ(serve(), 2u);
  EXPECT_EQ(ex.now(), period * 52 - kernel::Duration{1});
  EXPECT_EQ(board.stats().jumps, 0u);
  send_ir(*sim_end, 102);  // 51 on: one period
  EXPECT_EQ(serve(), 1u);
  EXPECT_EQ(ex.now(), period * 53 - kernel::Duration{1});
  send_ir(*sim_end, kHilMaxSequence);  // the last number there is: one period too
  EXPECT_EQ(serve(), 1u);
  EXPECT_EQ(ex.now(), period * 54 - kernel::Duration{1});
  auto s = board.stats();
  EXPECT_EQ(s.jumps, 2u);
  EXPECT_EQ(s.frames, 4u);
  EXPECT_EQ(s.missed, 49u + 50u + (kHilMaxSequence - 103u));
  ASSERT_FALSE(events.empty());
  EXPECT_NE(events.back().find("periods ahead of the node: its clock moves one period"), std::string::npos)
      << events.back();
  // A new run after it starts from the node's time again.
  send_ir(*sim_end, 0);
  send_ir(*sim_end, 1);
  EXPECT_EQ(serve(), 1u);
  EXPECT_EQ(ex.now(), period * 55 - kernel::Duration{1});
  std::vector<std::uint32_t> seqs;
  for (const HilWheelFrame& w : answers(*sim_end, 7)) seqs.push_back(w.seq);
  EXPECT_EQ(seqs, (std::vector<std::uint32_t>{0, 1, 51, 102, kHilMaxSequence, 0, 1}));
}

TEST(HilRobotBoard, ABadPeriodIsRefused) {
  auto [a, b] = io::make_loopback_pair("hil2-period");
  std::shared_ptr<io::IOStream> end = std::move(b);
  kernel::VirtualTimeExecutor ex;
  FrameClockBoardOptions bo;
  bo.control_period = kernel::Duration{0};
  EXPECT_THROW(HilRobotBoard(ex, end, bo), std::invalid_argument);
  bo.control_period = 2s;
  EXPECT_THROW(HilRobotBoard(ex, end, bo), std::invalid_argument);
  bo.control_period = 30ms;
  bo.lost_periods = 0;
  EXPECT_THROW(HilRobotBoard(ex, end, bo), std::invalid_argument);
  bo.lost_periods = 10;
  bo.max_catch_up = 0;
  EXPECT_THROW(HilRobotBoard(ex, end, bo), std::invalid_argument);
}

}  // namespace
