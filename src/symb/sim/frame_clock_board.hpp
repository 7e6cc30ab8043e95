// FrameClockBoard: the board side of a hardware-in-the-loop pair whose node runs on a clock the
// simulator's frames drive (docs/hil.md), whatever the frames carry: a 2D robot's IR
// (HilRobotBoard, `symb board --lockstep`) or a 3D module's sensors (mujoco::HilModuleBoard). What
// a kind of board says is its own (the decoding of a sensor frame, the devices it publishes to,
// its answer); the clock, the sequence numbers, the link's health and the statistics are here.
//
// Time: the node runs on a VirtualTimeExecutor. A clock activity stands where the world's runner
// stands in process (the same priority, at the control period): its tick k publishes sensor
// frame k, stamped with the tick's node time. When sensor frame k arrives, serve() runs the
// executor up to just before tick k + 1, which is everything the node does before the world's
// next step in process, and then the board answers. So every act of the node (a controller's own
// ticks, an actuator's watchdog) falls where it falls in process, however late a frame comes or
// however long the board is kept off its core: a board that gets every frame computes exactly
// what the node computes in process, bit for bit. A frame that never came (a corrupted one)
// leaves its tick without readings, as a sensor that missed a sample; the node goes on with the
// last ones, and its time still advances with the next frame.
//
// Sequence numbers (io::FrameSequence, the words the wall-clock board logs): 0 is the handshake,
// answered at once and never run; one not newer than the last is dropped (out of order); numbers
// skipped are missed. A handshake after frames of a run is a new run: the node's time cannot go
// back, so the new run's frame k is k periods after the last tick the node ran, and the node
// keeps its state. A frame more than max_catch_up periods ahead of the node (a simulator that went
// on without this board for a long while, or a peer's nonsense) moves the node's clock by one
// period and is counted a jump: no frame makes the board run more than max_catch_up periods.
//
// Threads: everything runs on the caller's thread (serve() drives the executor). The statistics
// may be read from any thread.
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

namespace symb::sim {

struct FrameClockBoardOptions {
  kernel::Duration control_period = std::chrono::milliseconds(30);
  // The link counts as lost after this many control periods of wall time without a sensor frame.
  int lost_periods = 10;
  // The most periods one frame may move the node's clock (see the header's comment).
  std::uint32_t max_catch_up = 1000;
  // Receives the board's own events: "link up", "link lost", "link back after 120 ms ...", a new
  // run, a jump.
  std::function<void(const std::string&)> on_event;
};

struct FrameClockStats {
  io::FrameStats decoder;          // dropped(): frames the CRC or the framing refused
  std::uint64_t bytes_in = 0;      // bytes read from the line
  std::uint64_t frames = 0;        // sensor frames passed to the node (handshakes not counted)
  std::uint64_t malformed = 0;     // good frames that are no sensor frame of this board
  std::uint64_t out_of_order = 0;  // sequence not newer than the last one: dropped
  std::uint64_t missed = 0;        // sequence numbers skipped (lost or corrupted frames)
  std::uint64_t jumps = 0;         // frames over max_catch_up periods ahead: the clock moved one
  std::uint64_t handshakes = 0;    // seq 0 frames answered, new runs' not counted
  std::uint64_t restarts = 0;      // seq 0 after frames of a run: a new run began
  std::uint64_t answers = 0;       // answers the line took, the handshakes' included
  std::uint64_t write_errors = 0;  // answers the line did not take
  std::uint64_t link_losses = 0;
  std::uint64_t link_recoveries = 0;
  std::uint32_t last_seq = 0;

  std::uint64_t bad_frames() const { return decoder.dropped() + malformed; }
};

// "frames 2000 good, 1 bad (crc 1, malformed 0), 1 missed, 0 out of order, 0 jumps; answers 2001,
// not taken 0; runs 1; link lost 0, back 0". `answers_extra` goes after the answers' count
// (", docking 2").
std::string describe(const FrameClockStats& s, const std::string& answers_extra = {});

class FrameClockBoard {
 public:
  virtual ~FrameClockBoard();
  FrameClockBoard(const FrameClockBoard&) = delete;
  FrameClockBoard& operator=(const FrameClockBoard&) = delete;

  // Starts the clock (its first tick one period from now, as the runner's). Call once the node
  // is built; fails when the port cannot be opened.
  kernel::Status start();
  // Reads the line for up to `timeout` of wall time and handles every frame that came (each
  // sensor frame runs the node to its next step and is answered). Returns the sensor frames
  // handled; fails when the line is gone (end of stream, an I/O error): reopen it, and serve()
  // goes on with it.
  kernel::Result<std::size_t> serve(kernel::Duration timeout);

  FrameClockStats link_stats() const;
  const FrameClockBoardOptions& options() const { return options_; }

 protected:
  // A sensor frame as the board's kind decodes it.
  struct SensorFrame {
    std::uint32_t seq = 0;
    std::vector<float> values;
  };

  // `frame_name` names a sensor frame in the log ("IR frame"). Throws std::invalid_argument unless
  // the period is in (0, 1 s], lost_periods is positive and max_catch_up at least 1.
  FrameClockBoard(kernel::VirtualTimeExecutor& executor, std::shared_ptr<io::IOStream> port,
                  FrameClockBoardOptions options, std::string frame_name);

  // A good frame's sensor frame, or why it is not one of this board's.
  virtual kernel::Result<SensorFrame> decode(std::span<const std::byte> payload) const = 0;
  // On the clock's tick that carries `values` (the node's context), stamped `now`.
  virtual void publish(const std::vector<float>& values, kernel::Time now) = 0;
  // After the node ran to just before the next tick (or at once for a handshake): the answer to
  // frame `seq`. Returns whether the line took it (what send() returned).
  virtual bool answer(std::uint32_t seq) = 0;

  // Frames and writes `payload`; whether the line took it.
  bool send(const std::vector<std::byte>& payload);
  void event(const std::string& text);
  // A derived board's destructor calls this first: no tick may reach it once its members go.
  void stop_clock();

 private:
  class Clock;
  void handle(std::span<const std::byte> payload, std::size_t& handled);

  kernel::VirtualTimeExecutor& executor_;
  std::shared_ptr<io::IOStream> port_;
  const FrameClockBoardOptions options_;
  std::unique_ptr<Clock> clock_;
  kernel::WallClock wall_;      // what the link's silences are measured on
  io::FrameSequence sequence_;  // on wall_: a silent link is lost after lost_periods
  io::FrameDecoder decoder_{1024};
  std::vector<std::byte> buf_;
  std::vector<std::byte> frame_;
  bool started_ = false;
  // The clock's tick that carries seq 0 of the run being served: frame k is tick base_tick_ + k.
  std::int64_t base_tick_ = 0;
  mutable std::mutex stats_mu_;
  FrameClockStats stats_;
};

}  // namespace symb::sim
