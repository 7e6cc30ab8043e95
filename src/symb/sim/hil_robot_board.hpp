// HilRobotBoard: the board side of a 2D hardware-in-the-loop pair whose clock the simulator's
// frames drive (`symb board --lockstep`, docs/hil.md). It gives one robot's node the devices the
// world runner gives it in process, `ir` (a SimIrSensor) and `wheels` (a SimWheels), but fed from
// and answering to a serial line in the 2D protocol (hil_protocol.hpp), so the robot's
// RobotSystem is built exactly as in process (RobotDevices{ir, wheels}) and runs the same task
// graph: the default device tasks, the actuator sink's watchdog included.
//
// Time: the node runs on a VirtualTimeExecutor. A clock activity stands where the WorldRunner
// stands in process (the same priority, at the control period): its tick k publishes IR frame k,
// stamped with the tick's node time. When IR frame k arrives, serve() runs the executor up to just
// before tick k + 1, which is everything the node does before the world's next step in process,
// and answers [k, left, right] with the wheels' output then. So every act of the node (the
// controller's own ticks, the watchdog) falls where it falls in process, however late a frame
// comes or however long the board is kept off its core, and with `symb sim --lockstep` the run is
// the in-process one bit for bit. A frame that never came (a corrupted one) leaves its tick
// without readings, as a sensor that missed a sample: the node goes on with the last ones.
//
// This is the 3D board's clock (mujoco/hil_module_board.hpp) for the 2D protocol. The board on
// the wall clock (board_link.hpp, the paper's task graph on OS threads) is the other way to run a
// 2D board: it shows how a control system copes with real time, this one checks that it computes
// what it computes in process.
//
// A new run (a handshake, seq 0, after frames of an earlier one) is served too: the node's time
// cannot go back, so the new run's tick k is k periods after the last tick of the old one, and the
// node keeps its state, as a board on the wall clock does.
//
// Threads: everything runs on the caller's thread (serve() drives the executor). stats() may be
// read from any thread.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include "symb/io/frame_codec.hpp"
#include "symb/io/frame_sequence.hpp"
#include "symb/io/stream.hpp"
#include "symb/kernel/clock.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/sim/robot_system.hpp"
#include "symb/sim/sim_drivers.hpp"

namespace symb::sim {

struct HilRobotBoardOptions {
  kernel::Duration control_period = std::chrono::milliseconds(30);
  // The link counts as lost after this many control periods of wall time without an IR frame.
  int lost_periods = 10;
  // Receives the board's own events, in the words of the board on the wall clock
  // (io::FrameSequence): "link up", "link lost", "link back after 120 ms ...", a new run.
  std::function<void(const std::string&)> on_event;
};

struct HilRobotBoardStats {
  io::FrameStats decoder;          // dropped(): frames the CRC or the framing refused
  std::uint64_t bytes_in = 0;      // bytes read from the line
  std::uint64_t frames = 0;        // IR frames passed to the node (handshakes not counted)
  std::uint64_t malformed = 0;     // good frames that are no IR frame (count, sequence, NaN)
  std::uint64_t out_of_order = 0;  // sequence not newer than the last one: dropped
  std::uint64_t missed = 0;        // sequence numbers skipped (lost or corrupted frames)
  std::uint64_t handshakes = 0;    // seq 0 frames answered
  std::uint64_t restarts = 0;      // seq 0 after frames of a run: a new run began
  std::uint64_t answers = 0;       // wheel frames the line took, the handshakes' included
  std::uint64_t write_errors = 0;  // wheel frames the line did not take
  std::uint64_t link_losses = 0;
  std::uint64_t link_recoveries = 0;
  std::uint32_t last_seq = 0;

  std::uint64_t bad_frames() const { return decoder.dropped() + malformed; }
};

// "frames 2000 good, 1 bad (crc 1, malformed 0), 1 missed, 0 out of order; answers 2001, ..."
std::string describe(const HilRobotBoardStats& s);

class HilRobotBoard {
 public:
  // Throws std::invalid_argument unless the period is in (0, 1 s] and lost_periods is positive.
  HilRobotBoard(kernel::VirtualTimeExecutor& executor, std::shared_ptr<io::IOStream> port,
                HilRobotBoardOptions options = {});
  ~HilRobotBoard();
  HilRobotBoard(const HilRobotBoard&) = delete;
  HilRobotBoard& operator=(const HilRobotBoard&) = delete;

  // The devices, for RobotSystem::build; and both, for a shell's device table.
  RobotDevices devices() const;
  std::vector<std::shared_ptr<io::Device>> device_list() const;

  // Starts the clock (its first tick one period from now, as the runner's). Call once the node
  // is built; fails when the port cannot be opened.
  kernel::Status start();
  // Reads the line for up to `timeout` of wall time and handles every frame that came (each IR
  // frame runs the node to its next step and answers). Returns the IR frames handled; fails when
  // the line is gone (end of stream, an I/O error): reopen it, and serve() goes on with it.
  kernel::Result<std::size_t> serve(kernel::Duration timeout);

  HilRobotBoardStats stats() const;

  struct Shared;  // the state the clock and the board share (public so the .cpp can name it)

 private:
  class Clock;
  void handle(std::span<const std::byte> payload, std::size_t& handled);
  void answer(std::uint32_t seq);
  void event(const std::string& text);

  kernel::VirtualTimeExecutor& executor_;
  std::shared_ptr<io::IOStream> port_;
  HilRobotBoardOptions options_;
  std::shared_ptr<Shared> shared_;
  std::unique_ptr<Clock> clock_;
  kernel::WallClock wall_;      // what the link's silences are measured on
  io::FrameSequence sequence_;  // on wall_: a silent link is lost after lost_periods
  io::FrameDecoder decoder_{1024};
  std::vector<std::byte> buf_;
  std::vector<std::byte> frame_;
  bool started_ = false;
  // The clock's tick that carries seq 0 of the run being served: frame k is tick base_tick_ + k.
  std::uint64_t base_tick_ = 0;
  mutable std::mutex stats_mu_;
  HilRobotBoardStats stats_;
};

}  // namespace symb::sim
