// The hardware-in-the-loop pieces of the sim layer, without processes: the protocol's frames and
// their refusals, the fault injector's promise (one corrupted frame = exactly one bad frame at a
// decoder, nothing lost around it), the board's device tasks over a real pseudo-terminal driven
// by a hand-written simulator, and the HilSimulator against a silent board.
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include <gtest/gtest.h>

#include "symb/io/pty_pair.hpp"
#include "symb/io/stream_task.hpp"
#include "symb/kernel/thread_executor.hpp"
#include "symb/os/node.hpp"
#include "symb/sim/board_link.hpp"
#include "symb/sim/enki_world.hpp"
#include "symb/sim/hil_protocol.hpp"
#include "symb/sim/hil_simulator.hpp"
#include "symb/sim/scenario.hpp"

#include "support/eventually.hpp"

namespace symb::sim {
namespace {

using namespace std::chrono_literals;
using symb::testing::eventually;

TEST(HilProtocol, FramesRoundTripAndBadOnesAreRefusedWithAReason) {
  HilIrFrame f;
  f.seq = 12345;
  for (std::size_t i = 0; i < kIrCount; ++i) f.ir[i] = 100.5f * static_cast<float>(i);
  auto back = decode_ir_payload(encode_ir_payload(f));
  ASSERT_TRUE(back.ok()) << back.error();
  EXPECT_EQ(back->seq, 12345u);
  EXPECT_EQ(back->ir, f.ir);

  auto w = decode_wheel_payload(encode_wheel_payload({7, 900.0f, -20.0f}));
  ASSERT_TRUE(w.ok());
  EXPECT_EQ(w->seq, 7u);
  EXPECT_EQ(w->left, 500.0f);  // clamped
  EXPECT_EQ(w->right, -20.0f);

  const float wrong_count[] = {1, 2};
  EXPECT_NE(decode_wheel_payload(io::encode_numbers(wrong_count)).error().find("expected 3 numbers, got 2"),
            std::string::npos);
  const float bad_seq[] = {1.5f, 0, 0};
  EXPECT_NE(decode_wheel_payload(io::encode_numbers(bad_seq)).error().find("bad sequence"), std::string::npos);
  const float nan_speed[] = {3, NAN, 0};
  EXPECT_FALSE(decode_wheel_payload(io::encode_numbers(nan_speed)).ok());
  HilIrFrame n = f;
  n.ir[3] = NAN;
  EXPECT_NE(decode_ir_payload(encode_ir_payload(n)).error().find("ir3 is NaN"), std::string::npos);
  const std::byte text[] = {std::byte{'h'}, std::byte{'i'}};
  EXPECT_NE(decode_ir_payload(text).error().find("not a number frame"), std::string::npos);
  EXPECT_FALSE(sequence_of(-1.0f));
  EXPECT_FALSE(sequence_of(static_cast<float>(kHilMaxSequence) + 2.0f));
  EXPECT_EQ(sequence_of(16777215.0f), 16777215u);
}

TEST(HilProtocol, EveryCorruptedFrameIsExactlyOneBadFrameAndNoOtherIsLost) {
  kernel::RandomStream data(5), split(6);
  FrameCorruptor corruptor(0.3, 42);
  std::vector<std::byte> stream, relayed;
  std::size_t sent = 0;
  // Frames of every shape: zeros in the values (COBS code bytes), large and tiny numbers.
  for (std::uint32_t seq = 0; seq < 3000; ++seq) {
    HilIrFrame f;
    f.seq = seq;
    for (float& v : f.ir) v = data.below(3) == 0 ? 0.0f : static_cast<float>(data.uniform(0, kIrMax));
    io::encode_frame(encode_ir_payload(f), stream);
    ++sent;
  }
  // Through the corruptor in random chunks, as a relay reads them.
  for (std::size_t at = 0; at < stream.size();) {
    const std::size_t n = std::min<std::size_t>(stream.size() - at, 1 + split.below(100));
    corruptor.feed(std::span<const std::byte>(stream.data() + at, n), relayed);
    at += n;
  }
  ASSERT_EQ(relayed.size(), stream.size());
  io::FrameDecoder decoder;
  std::size_t good = 0;
  std::uint32_t expect_at_least = 0;
  decoder.feed(relayed, [&](std::span<const std::byte> p) {
    auto f = decode_ir_payload(p);
    ASSERT_TRUE(f.ok());
    EXPECT_GE(f->seq, expect_at_least);
    expect_at_least = f->seq + 1;
    ++good;
  });
  EXPECT_EQ(corruptor.frames(), sent);
  EXPECT_GT(corruptor.corrupted(), 700u);
  EXPECT_LT(corruptor.corrupted(), 1100u);
  EXPECT_EQ(decoder.stats().dropped(), corruptor.corrupted());
  EXPECT_EQ(good + corruptor.corrupted(), sent);
}

// A controller for the board tests: drives [ir0, -ir1] from each IR vector.
class EchoController final : public os::Task {
 protected:
  void on_message(const os::Message& m) override {
    if (m.numbers().size() == kIrCount) send(0, {m.numbers()[0], -m.numbers()[1]});
  }
};

struct Board {
  kernel::ThreadExecutor executor;
  os::Node node{executor, os::NodeConfig{"board", 1, 256, nullptr}};
  std::shared_ptr<BoardLink> link;

  explicit Board(std::shared_ptr<io::IOStream> port) {
    BoardLinkOptions o;
    o.control_period = 30ms;
    link = BoardLink::create(std::move(port), o);
    EXPECT_TRUE(link->make_device_tasks(node).ok());
    auto ctrl = node.create("controller", std::make_unique<EchoController>());
    EXPECT_TRUE(ctrl.ok());
    EXPECT_TRUE(node.hook(*node.find("ir"), *ctrl).ok());
    EXPECT_TRUE(node.hook(*ctrl, *node.find("wheels")).ok());
  }
  ~Board() { node.clear(); }
  bool logged(std::string_view text) {
    for (const auto& e : node.log().since(0))
      if (e.text.find(text) != std::string::npos) return true;
    return false;
  }
};

// The simulator's end, by hand.
struct FakeSim {
  std::shared_ptr<io::SerialPort> port;
  io::FrameDecoder decoder;
  std::vector<HilWheelFrame> got;

  // Whether a frame [seq, left, ...] came; the watchdog's [seq, 0, 0] may follow it.
  bool answered(std::uint32_t seq, float left) const {
    for (const auto& f : got)
      if (f.seq == seq && f.left == left) return true;
    return false;
  }

  void send(std::uint32_t seq, float ir0, float ir1) {
    HilIrFrame f;
    f.seq = seq;
    f.ir[0] = ir0;
    f.ir[1] = ir1;
    ASSERT_TRUE(port->write_all(io::encode_frame(encode_ir_payload(f))).ok());
  }
  void send_raw(std::span<const std::byte> payload) { ASSERT_TRUE(port->write_all(io::encode_frame(payload)).ok()); }
  // Reads wheel frames until `cond` holds (true) or 10 s passed (false): a test waits for what it
  // asserts, not for a while that is long enough on an idle machine.
  bool read_until(const std::function<bool()>& cond) {
    for (auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10); !cond();) {
      if (std::chrono::steady_clock::now() > end) return false;
      read_for(std::chrono::milliseconds(5));
    }
    return true;
  }
  // Reads wheel frames for `d`.
  void read_for(kernel::Duration d) {
    std::vector<std::byte> buf(1024);
    for (auto end = std::chrono::steady_clock::now() + d; std::chrono::steady_clock::now() < end;) {
      auto n = port->read_some(buf, 5ms);
      if (!n || *n == 0) continue;
      decoder.feed(std::span<const std::byte>(buf.data(), *n), [&](std::span<const std::byte> p) {
        auto f = decode_wheel_payload(p);
        ASSERT_TRUE(f.ok()) << f.error();
        got.push_back(*f);
      });
    }
  }
};

TEST(BoardLinkTest, AnswersEchoTheSequenceAndBadInputIsCountedNotFatal) {
  auto pty = io::PtyPair::open("hil");
  ASSERT_TRUE(pty.ok()) << pty.error();
  Board board(pty->slave);
  FakeSim sim{pty->master, io::FrameDecoder(256), {}};

  for (std::uint32_t seq = 0; seq <= 5; ++seq) {
    sim.send(seq, 100.0f * static_cast<float>(seq), 5000.0f);  // ir1 above kIrMax: clamped
    sim.read_for(30ms);
  }
  ASSERT_TRUE(sim.read_until([&] { return sim.answered(5, 500.0f); }));
  ASSERT_FALSE(sim.got.empty());
  HilWheelFrame last{};
  for (const auto& f : sim.got)
    if (f.seq == 5 && f.left != 0.0f) last = f;
  EXPECT_EQ(last.left, 500.0f);    // 100 * 5, in range
  EXPECT_EQ(last.right, -500.0f);  // -kIrMax clamped to the wheel range
  bool saw_three = false;
  for (const auto& f : sim.got) saw_three = saw_three || (f.seq == 3 && f.left == 300.0f);
  EXPECT_TRUE(saw_three);

  // Out of order, a gap, a malformed frame, a corrupted frame.
  sim.send(4, 0, 0);
  sim.send(9, 10, 0);
  const float two[] = {1, 2};
  sim.send_raw(io::encode_numbers(two));
  std::vector<std::byte> bad = io::encode_frame(encode_ir_payload(HilIrFrame{10, {}}));
  kernel::RandomStream r(3);
  ASSERT_TRUE(corrupt_frame(bad, r));
  ASSERT_TRUE(pty->master->write_all(bad).ok());
  sim.send(11, 20, 0);
  // The controller sends only on input, so the watchdog stops the wheels 45 ms after seq 11's
  // answer: wait for that stop, the last thing the board does here.
  ASSERT_TRUE(sim.read_until(
      [&] { return sim.answered(11, 20.0f) && sim.got.back().seq == 11u && sim.got.back().left == 0.0f; }));
  const BoardLinkStats s = board.link->stats();
  EXPECT_EQ(s.ir_frames, 8u);  // 0..5, 9, 11
  EXPECT_EQ(s.out_of_order, 1u);
  EXPECT_EQ(s.missed, 4u);  // 6, 7, 8, 10
  EXPECT_EQ(s.malformed, 1u);
  EXPECT_EQ(s.decoder.dropped(), 1u);
  EXPECT_EQ(s.bad_frames(), 2u);
  EXPECT_EQ(s.last_seq, 11u);
  EXPECT_TRUE(board.logged("out-of-order"));
  EXPECT_TRUE(board.logged("malformed"));
}

// A board that falls behind (here its ir task held back, as a starved process would be) keeps
// the newest IR frames, and its books say how many it let go: every frame sent is handled or
// stale, and every skipped sequence number is a stale frame.
TEST(BoardLinkTest, ABoardThatFallsBehindKeepsTheNewestFramesAndCountsTheStaleOnes) {
  auto pty = io::PtyPair::open("hil");
  ASSERT_TRUE(pty.ok()) << pty.error();
  Board board(pty->slave);
  FakeSim sim{pty->master, io::FrameDecoder(256), {}};
  const os::TaskId ir = *board.node.find("ir");
  const auto offered = [&] { return board.node.info(ir)->traffic.attempted; };

  sim.send(0, 10, 0);
  ASSERT_TRUE(sim.read_until([&] { return sim.answered(0, 10.0f); }));
  ASSERT_TRUE(board.node.suspend(ir).ok());
  constexpr std::uint32_t kBurst = 20;
  for (std::uint32_t seq = 1; seq <= kBurst; ++seq) sim.send(seq, static_cast<float>(seq), 0);
  ASSERT_TRUE(sim.read_until([&] { return offered() == kBurst + 1; })) << offered() << " frames offered";
  const std::size_t capacity = board.node.info(ir)->queue_capacity;
  ASSERT_LT(capacity, kBurst);
  ASSERT_TRUE(board.node.resume(ir).ok());
  ASSERT_TRUE(sim.read_until([&] { return sim.answered(kBurst, static_cast<float>(kBurst)); }));
  // The count is refreshed at the ir task's next tick.
  ASSERT_TRUE(sim.read_until([&] { return board.link->stats().stale == kBurst - capacity; }))
      << board.link->stats().stale;
  const BoardLinkStats s = board.link->stats();
  EXPECT_EQ(s.ir_frames, 1 + capacity);
  EXPECT_EQ(s.ir_frames + s.stale, kBurst + 1u);
  EXPECT_EQ(s.missed, s.stale);
  EXPECT_EQ(s.last_seq, kBurst);
  EXPECT_FALSE(sim.answered(1, 1.0f));  // the oldest went unhandled
  EXPECT_NE(describe(s).find("missed (" + std::to_string(s.stale) + " stale)"), std::string::npos) << describe(s);
}

TEST(BoardLinkTest, SilenceIsReportedTheWheelsStopAndFramesBringItBack) {
  auto pty = io::PtyPair::open("hil");
  ASSERT_TRUE(pty.ok()) << pty.error();
  Board board(pty->slave);
  FakeSim sim{pty->master, io::FrameDecoder(256), {}};
  for (std::uint32_t seq = 0; seq < 5; ++seq) {
    sim.send(seq, 250, 0);
    sim.read_for(30ms);
  }
  sim.got.clear();
  // Silence: more than 10 periods, until the board says the link is lost.
  ASSERT_TRUE(sim.read_until([&] { return board.logged("link lost: no IR frame"); }));
  ASSERT_TRUE(sim.read_until([&] { return !sim.got.empty(); }));  // the watchdog's stop
  BoardLinkStats s = board.link->stats();
  EXPECT_FALSE(s.link_up);
  EXPECT_EQ(s.link_losses, 1u);
  EXPECT_GE(s.watchdog_stops, 1u);
  EXPECT_TRUE(board.logged("link lost: no IR frame"));
  // The watchdog's stop went out on the line, with the last sequence number.
  ASSERT_FALSE(sim.got.empty());
  EXPECT_EQ(sim.got.back().seq, 4u);
  EXPECT_EQ(sim.got.back().left, 0.0f);
  EXPECT_EQ(sim.got.back().right, 0.0f);

  sim.send(5, 120, 0);
  ASSERT_TRUE(sim.read_until([&] { return sim.answered(5, 120.0f); }));
  s = board.link->stats();
  EXPECT_TRUE(s.link_up);
  EXPECT_EQ(s.link_recoveries, 1u);
  EXPECT_TRUE(board.logged("link back after"));
  EXPECT_TRUE(sim.answered(5, 120.0f));

  // A new simulator run starts at seq 0 again: accepted, and said.
  sim.send(0, 30, 0);
  ASSERT_TRUE(sim.read_until([&] { return sim.answered(0, 30.0f); }));
  EXPECT_EQ(board.link->stats().restarts, 1u);
  EXPECT_TRUE(board.logged("started anew"));
  EXPECT_TRUE(sim.answered(0, 30.0f));
}

// A 2 m square without walls and one robot 'r' in its middle: nothing for the IR to see.
std::unique_ptr<EnkiWorld> open_arena_with_one_robot() {
  WorldSpec spec;
  spec.width = 200;
  spec.height = 200;
  auto world = std::make_unique<EnkiWorld>(spec, 1);
  world->add_robot("r", RobotKind::kThymio2, Pose{100, 100, 0});
  return world;
}

// A board at the slave end of `pty`, on a thread of its own until it is destroyed: each IR frame
// that arrives is handed to `answer`, and the wheel frame it returns (if any) is written back.
class ScriptedBoard {
 public:
  // `answer` gives the frames to write back for each IR frame read, in order (none: silence).
  ScriptedBoard(const io::PtyPair& pty, std::function<std::vector<HilWheelFrame>(const HilIrFrame&)> answer)
      : thread_([this, &pty, answer = std::move(answer)] {
          io::FrameDecoder d(256);
          std::vector<std::byte> buf(1024);
          while (!stop_) {
            auto n = pty.slave->read_some(buf, 5ms);
            if (!n || *n == 0) continue;
            d.feed(std::span<const std::byte>(buf.data(), *n), [&](std::span<const std::byte> p) {
              auto f = decode_ir_payload(p);
              if (!f) return;
              for (const HilWheelFrame& w : answer(*f))
                (void)pty.slave->write_all(io::encode_frame(encode_wheel_payload(w)));
            });
          }
        }) {}
  ~ScriptedBoard() { stop(); }
  ScriptedBoard(const ScriptedBoard&) = delete;
  ScriptedBoard& operator=(const ScriptedBoard&) = delete;
  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }

 private:
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// One robot in an empty arena, simulated in lockstep at 30 ms a step over a pseudo-terminal whose
// other end a ScriptedBoard plays; `left` is the robot's left wheel speed at each step.
struct LockstepRig {
  std::unique_ptr<EnkiWorld> world = open_arena_with_one_robot();
  std::optional<io::PtyPair> pty;
  std::unique_ptr<HilSimulator> simulator;
  std::vector<double> left;

  // The simulator with `o`, whose period and lockstep are set here.
  void open(const std::string& name, HilSimulatorOptions o) {
    auto p = io::PtyPair::open(name);
    ASSERT_TRUE(p.ok()) << p.error();
    pty = std::move(p).value();
    o.period = 30ms;
    o.lockstep = true;
    simulator = std::make_unique<HilSimulator>(*world, std::vector<std::shared_ptr<io::IOStream>>{pty->master}, o);
    simulator->add_observer([this](const StepRecord& r) { left.push_back(r.robots[0].state.left_speed); });
  }
};

// The hold is counted in steps, the same way at wall-clock pace and in lockstep. In lockstep every
// answer of the board's is on time however busy the box (at wall-clock pace a loaded box delays
// answers past a period of even 100 ms), and each silent step costs the answer wait.
TEST(HilSimulatorTest, ASilentBoardsRobotKeepsItsSpeedsForAWhileThenStops) {
  HilSimulatorOptions o;
  o.hold = 150ms;  // 5 steps
  o.answer_wait = 500ms;
  std::vector<std::string> events;
  o.on_event = [&](const std::string& e) { events.push_back(e); };
  LockstepRig rig;
  rig.open("hil", o);
  ASSERT_FALSE(HasFatalFailure());
  HilSimulator& simulator = *rig.simulator;
  const std::vector<double>& left = rig.left;

  // A board that answers the handshake and the first 10 steps with 300 units, then falls silent.
  ScriptedBoard board(*rig.pty, [](const HilIrFrame& f) -> std::vector<HilWheelFrame> {
    if (f.seq > 10) return {};
    return {HilWheelFrame{f.seq, 300, 300}};
  });
  ASSERT_TRUE(simulator.wait_for_boards(20s).ok());
  auto steps = simulator.run_for(18 * 30ms);  // 18 steps, the last 7 silent
  board.stop();
  ASSERT_TRUE(steps.ok()) << steps.error();
  ASSERT_EQ(left.size(), 18u);
  const double v = 300 * kCmPerSecondPerWheelUnit;
  EXPECT_EQ(left[0], 0.0);  // step 1 runs at rest: the handshake's answer is never applied
  for (std::size_t k = 2; k <= 11; ++k) EXPECT_NEAR(left[k - 1], v, 1e-9) << "step " << k;   // on answers 1 to 10
  for (std::size_t k = 12; k <= 15; ++k) EXPECT_NEAR(left[k - 1], v, 1e-9) << "step " << k;  // held
  for (std::size_t k = 16; k <= 18; ++k) EXPECT_EQ(left[k - 1], 0.0) << "step " << k;  // the fifth silent: stopped
  const auto s = simulator.stats()[0];
  EXPECT_EQ(s.silences, 1u);
  EXPECT_TRUE(s.silent);
  EXPECT_EQ(s.applied, 10u);
  EXPECT_EQ(s.missing, 8u);       // step 1 and the seven silent ones
  EXPECT_EQ(s.frames_sent, 19u);  // the handshake and one per step
  ASSERT_FALSE(events.empty());
  EXPECT_NE(events.back().find("board silent for 5 steps"), std::string::npos) << events.back();
}

// In lockstep a board slower than the period still drives every step: the simulator waits for
// the answer to the newest frame before each step, so step k runs on the answer to frame k - 1,
// never late and never missing; the handshake goes out once.
TEST(HilSimulatorTest, InLockstepABoardSlowerThanThePeriodAnswersEveryStepOnTime) {
  HilSimulatorOptions o;
  o.answer_wait = 20s;  // only a silent board waits it out
  LockstepRig rig;
  rig.open("hil-lockstep", o);
  ASSERT_FALSE(HasFatalFailure());
  HilSimulator& simulator = *rig.simulator;
  const std::vector<double>& left = rig.left;
  // Answers frame k with 10 k units, 50 ms after reading it (over a period late at wall-clock pace).
  ScriptedBoard board(*rig.pty, [](const HilIrFrame& f) -> std::vector<HilWheelFrame> {
    std::this_thread::sleep_for(50ms);
    const float units = 10.0f * static_cast<float>(f.seq);
    return {HilWheelFrame{f.seq, units, units}};
  });
  ASSERT_TRUE(simulator.wait_for_boards(20s).ok());
  auto steps = simulator.run_for(300ms);  // 10 steps
  board.stop();
  ASSERT_TRUE(steps.ok()) << steps.error();
  ASSERT_EQ(left.size(), 10u);
  EXPECT_EQ(left[0], 0.0);  // step 1 runs at rest: the handshake's answer is never applied
  for (std::size_t k = 2; k <= 10; ++k)
    EXPECT_NEAR(left[k - 1], 10.0 * static_cast<double>(k - 1) * kCmPerSecondPerWheelUnit, 1e-9) << "step " << k;
  const auto s = simulator.stats()[0];
  EXPECT_EQ(s.applied, 9u);
  EXPECT_EQ(s.late, 0u);
  EXPECT_EQ(s.missing, 1u);       // step 1
  EXPECT_EQ(s.frames_sent, 11u);  // one handshake, one frame per step
  EXPECT_EQ(simulator.overruns(), 0u);
}

// An answer that comes after its step's wait (here held back on purpose) and arrives with the next
// one is overtaken: the step takes the newer, and the older is counted superseded, so that every
// wheel frame received is applied, stale or superseded. The board answers odd frames only
// together with the next even one: the even steps wait in vain, the odd ones find two answers.
TEST(HilSimulatorTest, AnAnswerOvertakenByTheNextIsCountedSuperseded) {
  HilSimulatorOptions o;
  o.answer_wait = 500ms;  // waited out on each even step
  LockstepRig rig;
  rig.open("hil-superseded", o);
  ASSERT_FALSE(HasFatalFailure());
  HilSimulator& simulator = *rig.simulator;
  const std::vector<double>& left = rig.left;
  ScriptedBoard board(*rig.pty, [](const HilIrFrame& f) -> std::vector<HilWheelFrame> {
    const float units = 10.0f * static_cast<float>(f.seq);
    if (f.seq == 0) return {HilWheelFrame{0, 0, 0}};
    if (f.seq % 2 == 1) return {};
    return {HilWheelFrame{f.seq - 1, units - 10, units - 10}, HilWheelFrame{f.seq, units, units}};
  });
  ASSERT_TRUE(simulator.wait_for_boards(20s).ok());
  auto steps = simulator.run_for(300ms);  // 10 steps, frames 1 to 10
  board.stop();
  ASSERT_TRUE(steps.ok()) << steps.error();
  ASSERT_EQ(left.size(), 10u);
  // Step k runs on the answer to frame k - 1 when k - 1 is even; otherwise on the speeds before.
  for (std::size_t k = 3; k <= 9; k += 2) {
    const double v = 10.0 * static_cast<double>(k - 1) * kCmPerSecondPerWheelUnit;
    EXPECT_NEAR(left[k - 1], v, 1e-9) << "step " << k;
    EXPECT_NEAR(left[k], v, 1e-9) << "step " << k + 1 << " keeps it";
  }
  const auto s = simulator.stats()[0];
  EXPECT_EQ(s.applied, 4u);     // steps 3, 5, 7 and 9, on answers 2, 4, 6 and 8
  EXPECT_EQ(s.superseded, 4u);  // answers 1, 3, 5 and 7
  EXPECT_EQ(s.missing, 6u);     // step 1 and the even steps
  EXPECT_EQ(s.late, 0u);
  EXPECT_EQ(s.stale, 0u);
  EXPECT_EQ(s.received, 1u + s.applied + s.superseded);  // the handshake's answer, and the rest
}

// A frame the board wrote for the run before (its watchdog's stop, [66, 0, 0]) can still be on its
// way when a new run starts: held in `symb link`'s relay, it survives the flush of the
// simulator's own line. It is no answer to the handshake, which goes out again until the board
// answers seq 0, and it is not applied (it would make this run's answers look stale). Here it
// comes in place of the answer to the first handshake.
TEST(HilSimulatorTest, AFrameLeftFromAnEarlierRunIsNoAnswerToTheHandshake) {
  HilSimulatorOptions o;
  o.answer_wait = 200ms;  // the handshake's resend interval in lockstep
  LockstepRig rig;
  rig.open("hil-leftover", o);
  ASSERT_FALSE(HasFatalFailure());
  HilSimulator& simulator = *rig.simulator;
  int handshakes = 0;  // the board's thread only
  std::atomic<bool> answered_handshake{false};
  ScriptedBoard board(*rig.pty, [&](const HilIrFrame& f) -> std::vector<HilWheelFrame> {
    if (f.seq == 0 && handshakes++ == 0) return {HilWheelFrame{66, 0, 0}};
    if (f.seq == 0) answered_handshake = true;
    return {HilWheelFrame{f.seq, 100, 100}};
  });
  ASSERT_TRUE(simulator.wait_for_boards(20s).ok());
  EXPECT_TRUE(answered_handshake.load()) << "the board had not answered this run's handshake";
  auto steps = simulator.run_for(5 * 30ms);
  board.stop();
  ASSERT_TRUE(steps.ok()) << steps.error();
  ASSERT_EQ(rig.left.size(), 5u);
  EXPECT_EQ(rig.left[0], 0.0);
  for (std::size_t k = 2; k <= 5; ++k)
    EXPECT_NEAR(rig.left[k - 1], 100 * kCmPerSecondPerWheelUnit, 1e-9) << "step " << k;
  const auto s = simulator.stats()[0];
  EXPECT_EQ(s.stale, 1u);  // the frame from the earlier run
  EXPECT_EQ(s.applied, 4u);
  EXPECT_EQ(s.late, 0u);
  EXPECT_EQ(s.frames_sent, 7u);  // two handshakes, five steps
}

// A serial path that goes away and comes back, as a USB adapter's does when it is pulled and
// plugged in again: a symlink to a pseudo-terminal, removed with the pseudo-terminal, then made
// again to a new one.
struct Replug {
  std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("symb-replug-" + std::to_string(::getpid()) + "-" +
                                                ::testing::UnitTest::GetInstance()->current_test_info()->name());
  std::optional<io::PtyPair> pty;

  Replug() { plug(); }
  ~Replug() { std::filesystem::remove(path); }
  void plug() {
    auto p = io::PtyPair::open("replug");
    ASSERT_TRUE(p.ok()) << p.error();
    pty = std::move(p).value();
    std::filesystem::remove(path);
    std::filesystem::create_symlink(pty->slave_path, path);
  }
  void unplug() {
    std::filesystem::remove(path);
    pty->master->close();
    pty->slave->close();
    pty.reset();
  }
};

TEST(BoardLinkTest, ALineThatGoesAwayIsReopenedAndNothingIsCountedSentIntoIt) {
  Replug line;
  auto port = std::make_shared<io::SerialPort>("uart0", line.path.string());
  ASSERT_TRUE(port->open().ok());
  Board board(port);
  FakeSim sim{line.pty->master, io::FrameDecoder(256), {}};
  sim.send(0, 100, 0);
  ASSERT_TRUE(eventually([&] {
    sim.read_for(10ms);
    return sim.answered(0, 100.0f);
  }));

  line.unplug();
  ASSERT_TRUE(eventually([&] { return board.link->stats().line_losses == 1; }));
  BoardLinkStats s = board.link->stats();
  EXPECT_FALSE(s.line_open);
  // Commands while the line is down are not sent, and said so.
  const std::uint64_t written = s.frames_written;
  const auto wheels = *board.node.find("wheels");
  for (int i = 0; i < 3; ++i) {
    os::Message m;
    m.payload = os::Payload{50.0f, 50.0f};
    ASSERT_TRUE(board.node.post(wheels, m).ok());
  }
  ASSERT_TRUE(eventually([&] { return board.link->stats().frames_unsent >= 3; }));
  EXPECT_EQ(board.link->stats().frames_written, written);
  EXPECT_TRUE(board.logged("serial line 'uart0' down"));
  EXPECT_TRUE(board.logged("reopen attempt 1 failed"));

  std::this_thread::sleep_for(300ms);  // an outage long enough to measure
  line.plug();
  ASSERT_TRUE(eventually([&] { return board.link->stats().line_reopens == 1; }));
  s = board.link->stats();
  EXPECT_TRUE(s.line_open);
  EXPECT_GE(s.line_down, 300ms);
  EXPECT_LT(s.line_down, 5s);
  EXPECT_TRUE(board.logged("serial line 'uart0' open again after"));

  // The same path, a new device: frames flow both ways again.
  FakeSim again{line.pty->master, io::FrameDecoder(256), {}};
  for (std::uint32_t seq = 1; seq <= 3; ++seq) {
    again.send(seq, 200, 0);
    again.read_for(40ms);
  }
  ASSERT_TRUE(eventually([&] {
    again.read_for(10ms);
    return again.answered(3, 200.0f);
  }));
  s = board.link->stats();
  EXPECT_GT(s.frames_written, written);
  EXPECT_EQ(s.line_losses, 1u);
  // Every wheel frame made was written or counted unsent, once the ones in flight have arrived.
  EXPECT_TRUE(eventually([&] {
    const BoardLinkStats x = board.link->stats();
    return x.frames_written + x.frames_unsent == x.wheel_commands + x.watchdog_stops;
  }));
}

TEST(HilSimulatorTest, ALineThatGoesAwayIsReopenedAndItsDowntimeCounted) {
  auto world_ptr = open_arena_with_one_robot();
  EnkiWorld& world = *world_ptr;
  Replug line;
  auto port = std::make_shared<io::SerialPort>("data.r", line.path.string());
  ASSERT_TRUE(port->open().ok());
  HilSimulatorOptions o;
  o.period = 30ms;
  std::mutex events_mu;
  std::vector<std::string> events;
  o.on_event = [&](const std::string& e) {
    std::lock_guard lock(events_mu);
    events.push_back(e);
  };
  HilSimulator simulator(world, {port}, o);
  std::atomic<std::uint64_t> ir_at_board{0};
  std::atomic<bool> stop{false};
  // The board's end: counts the IR frames that arrive on whatever device is plugged in.
  std::mutex pty_mu;
  std::thread board([&] {
    io::FrameDecoder d(256);
    std::vector<std::byte> buf(1024);
    while (!stop) {
      std::shared_ptr<io::SerialPort> master;
      {
        std::lock_guard lock(pty_mu);
        if (line.pty) master = line.pty->master;
      }
      if (!master) {
        std::this_thread::sleep_for(5ms);
        continue;
      }
      auto n = master->read_some(buf, 5ms);
      if (!n || *n == 0) continue;
      d.feed(std::span<const std::byte>(buf.data(), *n), [&](std::span<const std::byte> p) {
        if (decode_ir_payload(p).ok()) ir_at_board.fetch_add(1);
      });
    }
  });
  std::thread run([&] { (void)simulator.run_for(3s); });
  ASSERT_TRUE(eventually([&] { return ir_at_board.load() >= 5; }));
  {
    std::lock_guard lock(pty_mu);
    line.unplug();
  }
  ASSERT_TRUE(eventually([&] { return simulator.stats()[0].line_losses == 1; }));
  EXPECT_FALSE(simulator.stats()[0].line_open);
  ASSERT_TRUE(eventually([&] { return simulator.stats()[0].unsent >= 5; }));
  const std::uint64_t sent_while_down = simulator.stats()[0].frames_sent;
  {
    std::lock_guard lock(pty_mu);
    line.plug();
  }
  ASSERT_TRUE(eventually([&] { return simulator.stats()[0].line_reopens == 1; }));
  const std::uint64_t before = ir_at_board.load();
  ASSERT_TRUE(eventually([&] { return ir_at_board.load() >= before + 5; }));
  simulator.stop();
  run.join();
  stop = true;
  board.join();
  const HilRobotStats s = simulator.stats()[0];
  EXPECT_TRUE(s.line_open);
  EXPECT_GE(s.line_down, 3 * o.period);  // five frames counted unsent, one a period apart
  EXPECT_LT(s.line_down, 5s);
  EXPECT_GT(s.frames_sent, sent_while_down);
  std::lock_guard lock(events_mu);
  std::string all;
  for (const auto& e : events) all += e + "\n";
  EXPECT_NE(all.find("serial line 'data.r' down"), std::string::npos) << all;
  EXPECT_NE(all.find("serial line 'data.r' open again after"), std::string::npos) << all;
}

}  // namespace
}  // namespace symb::sim
