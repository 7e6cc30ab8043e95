// HilSimulator: the simulator side of a hardware-in-the-loop pair (the paper's Player/Stage
// controller, V-A; protocol in hil_protocol.hpp and docs/hil.md). It steps a World at the
// wall-clock pace of the control period and talks to one board per robot over a serial line:
//
//   handshake  [0, IR before the first step] every period until every board answered it with
//              seq 0 (a frame left on the line from an earlier run is no answer); the answers
//              are never applied, so step 1 runs with the wheels at rest, as in-process
//   each period k = 1, 2, ...:
//     1. read, WITHOUT blocking, whatever wheel frames arrived; keep the newest valid one (the
//        highest sequence; among equals the last to arrive) and set the robot's wheels from it;
//        frames older than one already applied (or newer than any sent) are stale and dropped;
//     2. step the world by one period;
//     3. send [k, IR after the step] to each board;
//     4. hand a StepRecord to the observers (a RunRecorder).
//
// So a board that answers within the period acts one period after it read, exactly like the
// in-process run (world_runner.hpp's latency contract), and the same seed gives the same
// trajectory for as long as every answer is on time. In lockstep (options.lockstep) item 1 first
// waits for the answers to frame k - 1 (up to answer_wait), and no step waits for the wall clock:
// every answer is on time, and with a board whose node runs on the frames (hil_robot_board.hpp)
// the run is the in-process one, bit for bit. A late answer (one for
// an older IR frame than the newest sent) is still used, and counted. A board that stays silent:
// the robot keeps its last speeds for `hold`, then stops, and it is reported; when frames come
// back it follows them again.
//
// A line whose device goes away (writes or reads fail: a USB adapter pulled, `symb link`
// stopped) is reported, reopened by its path with backoff and used again once it is back;
// frames meanwhile are counted unsent. stats() says how long each line was down.
//
// Fault injection: `corrupt` is the fraction of outgoing IR frames to corrupt (corrupt_frame,
// one byte, always caught by the CRC), drawn from a RandomStream seeded with `seed`.
//
// Threads: run_for() and wait_for_boards() run on the caller's thread and own the world while
// they run; stop() and stats() may be called from any thread.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "symb/io/frame_codec.hpp"
#include "symb/io/stream.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"
#include "symb/sim/hil_protocol.hpp"
#include "symb/sim/world.hpp"
#include "symb/sim/world_runner.hpp"

namespace symb::sim {

struct HilSimulatorOptions {
  kernel::Duration period = std::chrono::milliseconds(30);
  // A silent board's robot keeps its last speeds this long, then stops.
  kernel::Duration hold = std::chrono::milliseconds(300);
  double corrupt = 0;  // fraction of IR frames corrupted on purpose, [0, 1]
  std::uint64_t seed = 1;
  // Link events for the person ("robot r1: board silent ..."); called on the stepping thread.
  std::function<void(const std::string&)> on_event;
  // A line whose device went away is reopened by its path at once, then after reopen_first,
  // doubling up to reopen_most (io::ReopenBackoff); meanwhile its frames are counted unsent.
  kernel::Duration reopen_first = std::chrono::milliseconds(100);
  kernel::Duration reopen_most = std::chrono::seconds(2);
  // Lockstep: before each step, wait for every board's answer to the newest frame, up to
  // `answer_wait` of wall time, instead of keeping the wall-clock pace (steps follow each other
  // as soon as the answers are in). Every answer is then on time however busy the machine, and a
  // board whose node runs on the frames (HilRobotBoard) drives its robot exactly as in process
  // (docs/hil.md says what a board on the wall clock can still do between a frame and its
  // answer); a silent one costs each step the whole wait.
  bool lockstep = false;
  kernel::Duration answer_wait = std::chrono::seconds(1);
};

struct HilRobotStats {
  std::string robot;
  std::uint64_t frames_sent = 0;   // IR frames the line took, handshake included
  std::uint64_t corrupted = 0;     // of them, corrupted by the fault injector
  std::uint64_t write_errors = 0;  // frames the port did not take (the board is not reading)
  std::uint64_t unsent = 0;        // frames not written at all: the line was down
  // The serial line itself: lost when the device goes away, reopened by its path with backoff.
  std::uint64_t line_losses = 0;
  std::uint64_t line_reopens = 0;
  kernel::Duration line_down{0};  // in all, the outage in progress included
  bool line_open = true;
  std::uint64_t received = 0;   // good wheel frames
  std::uint64_t malformed = 0;  // good frames that are no wheel frame
  io::FrameStats decoder;       // dropped(): bad frames (CRC, framing)
  std::uint64_t applied = 0;    // steps that took new speeds from a frame
  std::uint64_t late = 0;       // ... that answered an older IR frame than the newest sent
  // Frames older than one already applied, or newer than any IR frame sent (left on the line
  // from an earlier run): dropped.
  std::uint64_t stale = 0;
  // Frames overtaken by a newer one before a step took them (an answer that came after its own
  // step's wait, then with the next): with applied and stale, every wheel frame received but the
  // handshake's answers.
  std::uint64_t superseded = 0;
  std::uint64_t missing = 0;     // steps with no new frame (the last speeds kept)
  std::uint64_t silences = 0;    // times the board fell silent for `hold` (robot stopped)
  std::uint64_t recoveries = 0;  // times it answered again after that
  bool silent = false;
  bool answered = false;  // the handshake was answered
  std::uint32_t last_applied = 0;

  std::uint64_t bad_frames() const { return decoder.dropped() + malformed; }
};

// "sent 2000 (100 corrupted), received 3998 good, 0 bad; applied 1999, 1 late, ..."
std::string describe(const HilRobotStats& s);

class HilSimulator {
 public:
  // One port per robot of `world`, in robot order. Ports are opened (if closed), their unread
  // input flushed, and those that are file descriptors get a short write timeout, so a board
  // that does not read costs the step a few milliseconds at most. Throws std::invalid_argument
  // on a wrong port count, a period outside (0, 1 s], `corrupt` outside [0, 1], a reopen
  // backoff that is not positive and ascending, or lockstep without a positive answer_wait.
  HilSimulator(World& world, std::vector<std::shared_ptr<io::IOStream>> ports, HilSimulatorOptions options);
  ~HilSimulator();
  HilSimulator(const HilSimulator&) = delete;
  HilSimulator& operator=(const HilSimulator&) = delete;

  void add_observer(StepObserver observer);

  // The handshake: until every board answered, or `timeout`, or stop(). Fails on timeout.
  kernel::Status wait_for_boards(kernel::Duration timeout);
  // Steps the world duration / period times (in `duration` of wall-clock time, unless in
  // lockstep) or until stop().
  // Returns the steps done. Fails when a port cannot be opened or the sequence space is used up.
  kernel::Result<std::uint64_t> run_for(kernel::Duration duration);
  void stop() { stop_.store(true); }
  bool stopped() const { return stop_.load(); }

  std::vector<HilRobotStats> stats() const;
  // Steps that began more than a period after their due time (a loaded machine).
  std::uint64_t overruns() const { return overruns_.load(); }
  std::uint64_t steps() const { return steps_.load(); }

 private:
  struct Robot;
  kernel::Status open_ports();
  void send_ir(std::size_t robot, std::uint32_t seq);
  // Notices a line that went away and reopens it with backoff (before each step).
  void watch_line(std::size_t robot);
  // Reads what arrived; returns the newest valid wheel frame with seq >= 1. Does not block, unless
  // `want` > 0: then it first waits up to `wait` for a frame answering `want` (or a newer one).
  std::optional<HilWheelFrame> read_wheels(std::size_t robot, bool& any_frame, std::uint32_t want = 0,
                                           kernel::Duration wait = kernel::Duration{0});
  void event(const std::string& text);

  World& world_;
  HilSimulatorOptions options_;
  double dt_;
  std::uint64_t hold_steps_;
  std::vector<std::shared_ptr<io::IOStream>> ports_;
  std::vector<Robot> robots_;
  FrameCorruptor corruptor_;
  std::vector<std::byte> frame_;
  std::vector<std::byte> buf_;
  std::vector<StepObserver> observers_;
  std::uint32_t seq_ = 0;  // the newest IR frame sent
  mutable std::mutex stats_mu_;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> overruns_{0};
  std::atomic<std::uint64_t> steps_{0};
  bool opened_ = false;
};

}  // namespace symb::sim
