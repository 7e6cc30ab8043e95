// Hardware in the loop in 3D: one module of an organism runs on a board (HilModuleBoard, its own
// executor on its own thread) at the other end of a loopback serial line, the rest in process
// (HilOrganism over an OrganismSession). With every frame on time the organism moves exactly as
// in the in-process run, tick for tick, bit for bit (the board's node runs on the frames' clock);
// a connector latched and unlatched from the board's side acts on the world; corrupted frames are
// counted exactly and the run goes on; the protocol refuses what is not its frames.
#include "symb/sim/mujoco/hil_organism.hpp"

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "symb/io/frame_codec.hpp"
#include "symb/io/loopback_stream.hpp"
#include "symb/io/stream_task.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/sim/mujoco/hil_module_board.hpp"
#include "symb/sim/mujoco/hil_module_protocol.hpp"
#include "symb/sim/mujoco/organism_session.hpp"
#include "symb/sim/robot_system.hpp"
#include "symb/sim/scenario.hpp"

#include "support/eventually.hpp"
#include "support/measured.hpp"

namespace symb::sim::mujoco {
namespace {

using namespace std::chrono_literals;

// Two cubes docked head to tail: both drive forward; the tail (the board's module) also swings
// its hinge with an oscillator whose 20 ms ticks fall between the 30 ms frames.
constexpr const char* kHil3Pair = R"(name: hil_pair
seed: 3
duration: 6s
control_period: 30ms
world:
  kind: mujoco
  docked: [[head.back, tail.front]]
robots:
  - name: head
    module: modules/cube.yaml
    start: {x: 0, y: 0, heading: 0}
    tasks:
      - {name: controller, type: mdl2e, params: {program: mdl2e/organism_forward.mdl2e}}
    hooks:
      - controller -> wheels
  - name: tail
    module: modules/cube.yaml
    tasks:
      - {name: controller, type: mdl2e, params: {program: mdl2e/organism_forward.mdl2e}}
      - {name: swing, type: oscillator, params: {frequency: 1.3, amplitude: 0.6}}
    hooks:
      - controller -> wheels
      - swing -> hinge
)";

Scenario hil3_scenario() {
  auto sc = parse_scenario(kHil3Pair, std::string(SYMB_SCENARIO_DIR) + "/inline.yaml");
  EXPECT_TRUE(sc.ok()) << sc.error();
  return sc.ok() ? std::move(sc).value() : Scenario{};
}

struct Hil3Tick {
  std::vector<Pose3> poses;
  std::vector<double> hinges;
};

std::vector<Hil3Tick> hil3_in_process(const Scenario& sc, std::uint64_t ticks) {
  kernel::VirtualTimeExecutor ex;
  auto made = OrganismSession::create(sc, ex);
  EXPECT_TRUE(made.ok()) << made.error();
  std::vector<Hil3Tick> out;
  if (!made.ok()) return out;
  OrganismSession& s = **made;
  s.runner().add_observer([&](const MujocoStepRecord& r) {
    Hil3Tick t;
    for (const ModuleStep& m : r.modules) {
      t.poses.push_back(m.pose);
      t.hinges.push_back(m.hinge_angle);
    }
    out.push_back(std::move(t));
  });
  s.start();
  ex.run_until(sc.control_period * static_cast<std::int64_t>(ticks));
  return out;
}

// The board: the module's RobotSystem over the link's devices, served on its own thread (from
// `delay` on: a board slow to come up).
class Hil3Board {
 public:
  Hil3Board(const Scenario& sc, std::size_t module, std::shared_ptr<io::IOStream> port,
            std::chrono::milliseconds delay = std::chrono::milliseconds(0)) {
    HilModuleBoardOptions bo;
    bo.control_period = sc.control_period;
    board_ = std::make_unique<HilModuleBoard>(ex_, sc.robots[module].module_kind, std::move(port), bo);
    RobotSystemOptions ro;
    ro.control_period = sc.control_period;
    ro.seed = robot_node_seed(sc.seed, module);
    ro.read_program = file_program_reader(sc.base_dir);
    RobotDevices devices;
    devices.module = board_->device_lookups();
    auto built = RobotSystem::build(ex_, sc.robots[module], std::move(devices), std::move(ro));
    EXPECT_TRUE(built.ok()) << built.error();
    if (!built.ok()) return;
    system_ = std::move(built).value();
    EXPECT_TRUE(board_->start().ok());
    thread_ = std::thread([this, delay] {
      std::this_thread::sleep_for(delay);
      while (!stop_.load()) {
        auto got = board_->serve(5ms);
        if (!got.ok()) break;  // the simulator's end closed
      }
    });
  }
  ~Hil3Board() { join(); }
  void join() {
    stop_.store(true);
    if (thread_.joinable()) thread_.join();
  }
  HilModuleBoard& board() { return *board_; }
  // A device of the board by name (the shell's `ioctl` reaches it the same way).
  std::shared_ptr<io::Device> device(const std::string& name) {
    for (auto& d : board_->devices())
      if (d->name() == name) return d;
    return nullptr;
  }

 private:
  kernel::VirtualTimeExecutor ex_;
  std::unique_ptr<HilModuleBoard> board_;
  std::unique_ptr<RobotSystem> system_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

struct Hil3Pair {
  Scenario sc;
  kernel::VirtualTimeExecutor ex;
  std::unique_ptr<OrganismSession> session;
  std::unique_ptr<Hil3Board> board;
  std::unique_ptr<HilOrganism> hil;
  std::vector<Hil3Tick> ticks;
  std::shared_ptr<io::IOStream> board_line;  // the board's end, for a frame written beside it

  Hil3Pair(Scenario scenario, std::size_t module, HilOrganismOptions options,
           std::chrono::milliseconds board_delay = std::chrono::milliseconds(0))
      : sc(std::move(scenario)) {
    auto [a, b] = io::make_loopback_pair("hil3");
    std::shared_ptr<io::IOStream> sim_end = std::move(a), board_end = std::move(b);
    auto made = OrganismSession::create(sc, ex);
    EXPECT_TRUE(made.ok()) << made.error();
    if (!made.ok()) return;
    session = std::move(made).value();
    session->runner().add_observer([this](const MujocoStepRecord& r) {
      Hil3Tick t;
      for (const ModuleStep& m : r.modules) {
        t.poses.push_back(m.pose);
        t.hinges.push_back(m.hinge_angle);
      }
      ticks.push_back(std::move(t));
    });
    board_line = board_end;
    board = std::make_unique<Hil3Board>(sc, module, board_end, board_delay);
    auto h = HilOrganism::create(*session, ex, module, sim_end, std::move(options));
    EXPECT_TRUE(h.ok()) << h.error();
    if (!h.ok()) return;
    hil = std::move(h).value();
    EXPECT_TRUE(hil->wait_for_board(5s).ok());
  }
  ~Hil3Pair() {
    if (board) board->join();
    hil.reset();
    session.reset();
  }
};

HilOrganismOptions hil3_lockstep() {
  HilOrganismOptions o;
  o.paced = false;
  o.answer_wait = 5s;  // a loaded machine (a sanitizer build) must not make an answer late
  return o;
}

TEST(HilOrganism, TheBoardsModuleMovesTheOrganismExactlyAsInProcess) {
  const Scenario sc = hil3_scenario();
  ASSERT_EQ(sc.robots.size(), 2u);
  constexpr std::uint64_t kTicks = 200;  // 6 s
  const auto reference = hil3_in_process(sc, kTicks);
  ASSERT_EQ(reference.size(), kTicks);
  Hil3Pair pair(sc, 1, hil3_lockstep());
  ASSERT_TRUE(pair.hil);
  auto done = pair.hil->run_ticks(kTicks);
  ASSERT_TRUE(done.ok()) << done.error();
  EXPECT_EQ(*done, kTicks);
  ASSERT_EQ(pair.ticks.size(), kTicks);
  std::size_t identical = 0;
  double worst = 0;
  for (std::size_t k = 0; k < kTicks; ++k) {
    bool same = true;
    for (std::size_t m = 0; m < 2; ++m) {
      const auto& p = pair.ticks[k].poses[m].position;
      const auto& q = reference[k].poses[m].position;
      worst = std::max(worst, std::hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]));
      same = same && p == q && pair.ticks[k].hinges[m] == reference[k].hinges[m];
    }
    identical += same ? 1 : 0;
  }
  const auto st = pair.hil->stats();
  // The board counts a frame after its answer went out, so maybe not yet when the run returns.
  EXPECT_TRUE(symb::testing::eventually([&] { return pair.board->board().stats().frames >= kTicks; }));
  pair.board->join();
  const auto bs = pair.board->board().stats();
  std::printf("hil 3D: %zu of %llu ticks identical to in-process, worst distance %.3g m; sim: %s; board: %s\n",
              identical, static_cast<unsigned long long>(kTicks), worst, describe(st).c_str(), describe(bs).c_str());
  // Every frame on time: the same floats, tick for tick.
  EXPECT_EQ(identical, kTicks);
  EXPECT_EQ(worst, 0.0);
  EXPECT_EQ(st.late, 0u);
  EXPECT_EQ(st.missing, 0u);
  EXPECT_EQ(st.applied, kTicks - 1);  // the answer to the last frame comes after the run
  EXPECT_EQ(bs.frames, kTicks);
  EXPECT_EQ(bs.bad_frames(), 0u);
  EXPECT_EQ(bs.missed, 0u);
  // And the board's module did drive and swing: the tail moved forward with the head, its hinge
  // followed the oscillator.
  const Pose3 tail0 = reference.front().poses[1], tail1 = reference.back().poses[1];
  EXPECT_GT(tail1.position[0] - tail0.position[0], 0.1);
  double swing = 0;
  for (const auto& t : reference) swing = std::max(swing, std::abs(t.hinges[1]));
  EXPECT_GT(swing, 0.3);
}

// In lockstep the handshake waits as long as every answer does: a board that answers it six
// periods late (kept off its core, slow to come up) gets it once, and the books count one.
TEST(HilOrganism, InLockstepABoardSlowToAnswerTheHandshakeGetsItOnce) {
  const Scenario sc = hil3_scenario();
  Hil3Pair pair(sc, 1, hil3_lockstep(), 6 * std::chrono::duration_cast<std::chrono::milliseconds>(sc.control_period));
  ASSERT_TRUE(pair.hil);
  EXPECT_EQ(pair.hil->stats().frames_sent, 1u);
  constexpr std::uint64_t kTicks = 20;
  auto done = pair.hil->run_ticks(kTicks);
  ASSERT_TRUE(done.ok()) << done.error();
  const auto st = pair.hil->stats();
  pair.board->join();
  const auto bs = pair.board->board().stats();
  EXPECT_EQ(st.frames_sent, kTicks + 1);
  EXPECT_EQ(st.late + st.stale + st.missing, 0u);
  EXPECT_EQ(bs.frames, kTicks);
  EXPECT_EQ(bs.bad_frames(), 0u);
}

// A command numbered beyond any frame sent (one the board wrote for an earlier run, held up on
// the line) is stale, as in 2D: applied, it would have made every later answer of the run look
// older than it and the module would have stopped following its board.
TEST(HilOrganism, ACommandNewerThanAnyFrameSentIsStale) {
  const Scenario sc = hil3_scenario();
  Hil3Pair pair(sc, 1, hil3_lockstep());
  ASSERT_TRUE(pair.hil);
  auto first = pair.hil->run_ticks(5);
  ASSERT_TRUE(first.ok()) << first.error();
  const HilModuleLayout layout = HilModuleLayout::of(sc.robots[1].module_kind);
  ASSERT_TRUE(pair.board_line->write_all(io::encode_frame(encode_module_command(layout, {999, 0, 0, 0}))).ok());
  auto second = pair.hil->run_ticks(10);
  ASSERT_TRUE(second.ok()) << second.error();
  const auto st = pair.hil->stats();
  EXPECT_EQ(st.stale, 1u);
  EXPECT_EQ(st.applied, 14u);  // every tick after the first, on its own answer
  EXPECT_EQ(st.late, 0u);
  EXPECT_EQ(st.missing, 0u);
}

TEST(HilOrganism, ALatchAndAnUnlatchFromTheBoardReachTheWorld) {
  const Scenario sc = hil3_scenario();
  Hil3Pair pair(sc, 1, hil3_lockstep());
  ASSERT_TRUE(pair.hil);
  ASSERT_TRUE(pair.hil->run_ticks(5).ok());
  auto docked = [&] {
    std::optional<std::pair<std::size_t, std::size_t>> to;
    pair.session->runner().with_world([&](MujocoWorld& w) { to = w.docked_to(1, *w.find_connector(1, "front")); });
    return to;
  };
  ASSERT_TRUE(docked().has_value());
  auto front = pair.board->device("connector_front");
  ASSERT_NE(front, nullptr);
  // The board's shell or controller: `ioctl connector_front unlatch`.
  auto answer = front->ioctl("unlatch");
  ASSERT_TRUE(answer.ok()) << answer.error();
  EXPECT_EQ(*answer, "sent to the simulator");
  // The board sends it with its next answer; the simulator applies it before the next step.
  ASSERT_TRUE(pair.hil->run_ticks(3).ok());
  EXPECT_FALSE(docked().has_value());
  auto state = front->ioctl("state");
  ASSERT_TRUE(state.ok());
  EXPECT_EQ(state->rfind("docked", 0), std::string::npos) << *state;  // the board heard of it
  ASSERT_TRUE(front->ioctl("latch").ok());
  ASSERT_TRUE(pair.hil->run_ticks(3).ok());
  ASSERT_TRUE(docked().has_value());
  EXPECT_EQ(docked()->first, 0u);
  state = front->ioctl("state");
  ASSERT_TRUE(state.ok());
  EXPECT_EQ(*state, "docked to module 0, open") << *state;
  const auto st = pair.hil->stats();
  EXPECT_EQ(st.dock_commands, 2u);
  EXPECT_EQ(st.dock_refused, 0u);
  pair.board->join();
  EXPECT_EQ(pair.board->board().stats().dock_commands, 2u);
}

TEST(HilOrganism, CorruptedFramesAreCountedExactlyAndTheRunGoesOn) {
  const Scenario sc = hil3_scenario();
  constexpr std::uint64_t kTicks = 200;
  const auto reference = hil3_in_process(sc, kTicks);
  HilOrganismOptions o = hil3_lockstep();
  o.corrupt = 0.05;
  o.seed = 7;
  // A corrupted frame gets no answer: the simulator waits this long for it, then goes on.
  o.answer_wait = 300ms;
  Hil3Pair pair(sc, 1, o);
  ASSERT_TRUE(pair.hil);
  auto done = pair.hil->run_ticks(kTicks);
  ASSERT_TRUE(done.ok()) << done.error();
  EXPECT_EQ(*done, kTicks);
  const auto st = pair.hil->stats();
  pair.board->join();
  const auto bs = pair.board->board().stats();
  const double drove = pair.ticks.back().poses[1].position[0] - pair.ticks.front().poses[1].position[0];
  const double ref = reference.back().poses[1].position[0] - reference.front().poses[1].position[0];
  std::printf("hil 3D, 5%% corrupted: sim: %s; board: %s; tail drove %.3f m (in process %.3f m)\n",
              describe(st).c_str(), describe(bs).c_str(), drove, ref);
  EXPECT_GT(st.corrupted, 0u);
  // Exact by construction (corrupt_frame): one bad frame per corrupted one, nothing else lost.
  EXPECT_EQ(bs.bad_frames(), st.corrupted);
  EXPECT_EQ(bs.decoder.crc_errors + bs.decoder.bad_version, st.corrupted);
  EXPECT_EQ(bs.frames + bs.handshakes + bs.bad_frames(), st.frames_sent);
  // The frames after a lost one are the next sequence numbers: each loss is one missed number
  // (the last frame's loss, if any, is not known yet).
  EXPECT_LE(bs.missed, st.corrupted);
  EXPECT_GE(bs.missed + 1, st.corrupted);
  // Every tick but the first took a new answer or kept the last commands; every answer to a frame
  // was applied, found stale or overtaken by a newer one, but the last (its tick never comes).
  EXPECT_EQ(st.applied + st.missing, kTicks - 1);
  const std::uint64_t accounted = bs.handshakes + st.applied + st.stale + st.superseded;
  EXPECT_GE(st.received, accounted);
  EXPECT_LE(st.received, accounted + 1) << "only the last answer may be left, its tick never comes";
  // The simulator kept the last commands once for each frame the board never saw (the tick after a
  // lost last frame never comes), and once for each answer that came after its tick's wait (a
  // board kept off its core for 300 ms on a loaded machine), which a later tick then took late or
  // found overtaken.
  if (st.late + st.superseded == 0)
    EXPECT_EQ(st.missing, bs.missed);
  else
    EXPECT_LE(st.missing - bs.missed, st.late + st.superseded);
  EXPECT_GE(st.missing, bs.missed);
  // The organism went on: a lost frame keeps the last commands for one tick, so the distance is
  // the in-process one within 2%.
  EXPECT_NEAR(drove, ref, 0.02 * ref);
}

TEST(HilOrganismProtocol, FramesRoundTripAndRefuseWhatIsNotTheirs) {
  const Scenario sc = hil3_scenario();
  const HilModuleLayout layout = HilModuleLayout::of(sc.robots[1].module_kind);
  ASSERT_TRUE(layout.wheels);
  ASSERT_EQ(layout.connectors.size(), sc.robots[1].module_kind.connectors.size());
  HilModuleSensors s;
  s.seq = 42;
  for (std::size_t i = 0; i + 1 < layout.sensor_values(); ++i) s.values.push_back(0.25f * static_cast<float>(i));
  auto back = decode_module_sensors(layout, encode_module_sensors(s));
  ASSERT_TRUE(back.ok()) << back.error();
  EXPECT_EQ(back->seq, 42u);
  EXPECT_EQ(back->values, s.values);
  s.values.pop_back();
  auto short_frame = decode_module_sensors(layout, encode_module_sensors(s));
  ASSERT_FALSE(short_frame.ok());
  EXPECT_NE(short_frame.error().find("expected " + std::to_string(layout.sensor_values())), std::string::npos);

  HilModuleCommand c{7, -120.5f, 300.0f, 0.4f};
  auto cb = decode_board_frame(layout, encode_module_command(layout, c));
  ASSERT_TRUE(cb.ok()) << cb.error();
  EXPECT_FALSE(cb->dock);
  EXPECT_EQ(cb->command.seq, 7u);
  EXPECT_EQ(cb->command.left, -120.5f);
  EXPECT_EQ(cb->command.right, 300.0f);
  EXPECT_EQ(cb->command.hinge, 0.4f);
  HilModuleLayout hinge_only = layout;
  hinge_only.wheels = false;
  EXPECT_EQ(hinge_only.command_values(), 2u);
  EXPECT_FALSE(decode_board_frame(hinge_only, encode_module_command(layout, c)).ok());
  auto ho = decode_board_frame(hinge_only, encode_module_command(hinge_only, c));
  ASSERT_TRUE(ho.ok());
  EXPECT_EQ(ho->command.hinge, 0.4f);

  HilDockCommand d{9, 1, HilDockOp::kUnlatch};
  auto db = decode_board_frame(layout, encode_dock_command(d));
  ASSERT_TRUE(db.ok()) << db.error();
  EXPECT_TRUE(db->dock);
  EXPECT_EQ(db->dock_command.seq, 9u);
  EXPECT_EQ(db->dock_command.connector, 1u);
  EXPECT_EQ(db->dock_command.op, HilDockOp::kUnlatch);
  auto bytes = encode_dock_command({9, 200, HilDockOp::kLatch});
  auto no_connector = decode_board_frame(layout, bytes);
  ASSERT_FALSE(no_connector.ok());
  EXPECT_NE(no_connector.error().find("no connector 200"), std::string::npos) << no_connector.error();
  bytes = encode_dock_command(d);
  bytes[6] = std::byte{9};
  EXPECT_FALSE(decode_board_frame(layout, bytes).ok());
  bytes.pop_back();
  EXPECT_FALSE(decode_board_frame(layout, bytes).ok());
  const float nan_command[4] = {3, std::nanf(""), 0, 0};
  EXPECT_FALSE(decode_board_frame(layout, io::encode_numbers(nan_command)).ok());
  const float bad_seq[4] = {2.5f, 0, 0, 0};
  EXPECT_FALSE(decode_board_frame(layout, io::encode_numbers(bad_seq)).ok());
}

TEST(HilOrganism, TheBoardsModuleMayHaveNoEvents) {
  std::string text = kHil3Pair;
  text += "events:\n  - {at: 1s, robot: tail, shell: \"ioctl connector_front state\"}\n";
  auto sc = parse_scenario(text, std::string(SYMB_SCENARIO_DIR) + "/inline.yaml");
  ASSERT_TRUE(sc.ok()) << sc.error();
  kernel::VirtualTimeExecutor ex;
  auto session = OrganismSession::create(*sc, ex);
  ASSERT_TRUE(session.ok()) << session.error();
  auto [a, b] = io::make_loopback_pair("hil3-events");
  auto h = HilOrganism::create(**session, ex, 1, std::move(a));
  ASSERT_FALSE(h.ok());
  EXPECT_NE(h.error().find("inline.yaml:"), std::string::npos) << h.error();
  EXPECT_NE(h.error().find("its events belong to the board's shell"), std::string::npos) << h.error();
}

}  // namespace
}  // namespace symb::sim::mujoco
