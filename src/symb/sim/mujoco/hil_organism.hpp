// HilOrganism: the simulator side of a 3D hardware-in-the-loop pair (docs/hil.md, "3D: one
// module on a board"; frames in hil_module_protocol.hpp). An OrganismSession runs the organism in
// process, on a VirtualTimeExecutor, except one module, whose node is a board at the other end of
// a serial line: that module's node is emptied (its devices are the link's now), and each tick:
//
//   1. the newest command frame the board sent (the highest seq, the last among equals) sets the
//      module's hinge target and wheels; docking frames act on the module's connectors (latch,
//      unlatch, open, close) in the order they came, before the step, as an in-process ioctl acts
//      between two steps; their verdicts are counted and reported;
//   2. the executor runs to the tick: the world steps, the other modules' nodes run;
//   3. [k, ir, hinge, connectors after the step] goes to the board;
//   4. the simulator waits for the answer to k up to `answer_wait` of wall time (a paced run
//      then waits out the period), reading everything that came.
//
// So a board that answers each frame in time drives its module exactly as the module's node does
// in process (HilModuleBoard runs the node on the frames' clock): the same seed gives the same
// organism, bit for bit. Late answers (for an older frame than the newest sent) are still used,
// and counted; stale ones (older than one applied, or newer than any frame sent: written for an
// earlier run) are dropped; a silent board's module keeps its last commands for `hold`, then its
// wheels stop and its hinge holds its angle, and it is reported. The handshake is the 2D one:
// [0, readings before the first step] each period (each `answer_wait` when that is longer) until
// the board answers it with seq 0; the answer is never applied.
//
// A line whose device goes away (a USB adapter pulled, `symb link` stopped) is reported, reopened
// by its path with backoff and used again once it is back, as in 2D; stats() says how long it was
// down.
//
// Limits: the board's module has no events and no hooks over the organism bus (create() says so at
// the scenario's place); its imu, touch, laser and camera are not carried.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "symb/io/frame_codec.hpp"
#include "symb/io/reopen_backoff.hpp"
#include "symb/io/stream.hpp"
#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/sim/hil_protocol.hpp"
#include "symb/sim/mujoco/hil_module_protocol.hpp"
#include "symb/sim/mujoco/organism_session.hpp"

namespace symb::sim::mujoco {

struct HilOrganismOptions {
  // How long the simulator waits for the answer to a sensor frame (wall time).
  kernel::Duration answer_wait = std::chrono::milliseconds(30);
  // Keep the wall-clock pace: a step never begins before its due time (start + k periods).
  bool paced = true;
  // A silent board's module keeps its last commands this long (virtual time), then stops.
  kernel::Duration hold = std::chrono::milliseconds(300);
  double corrupt = 0;  // fraction of sensor frames corrupted on purpose (corrupt_frame), [0, 1]
  std::uint64_t seed = 1;
  std::function<void(const std::string&)> on_event;  // link events for the person
  // A line whose device went away is reopened by its path at once, then after reopen_first,
  // doubling up to reopen_most (io::ReopenBackoff), as in 2D; meanwhile frames are counted unsent.
  kernel::Duration reopen_first = std::chrono::milliseconds(100);
  kernel::Duration reopen_most = std::chrono::seconds(2);
};

struct HilOrganismStats {
  std::uint64_t frames_sent = 0;   // sensor frames the line took, handshake included
  std::uint64_t corrupted = 0;     // of them, corrupted by the fault injector
  std::uint64_t write_errors = 0;  // frames the line did not take
  std::uint64_t received = 0;      // good command frames
  std::uint64_t malformed = 0;     // good frames that are neither a command nor a docking frame
  io::FrameStats decoder;          // dropped(): bad frames (CRC, framing)
  std::uint64_t applied = 0;       // ticks that took new commands from a frame
  std::uint64_t late = 0;          // ... that answered an older frame than the newest sent
  std::uint64_t stale = 0;         // older than one already applied, or newer than any sent: dropped
  // Frames overtaken by a newer one before a tick took them (an answer that came after its own
  // tick's wait, then with the next): with applied and stale, every command frame received but
  // the handshake's answers and the newest (applied at the next tick).
  std::uint64_t superseded = 0;
  std::uint64_t missing = 0;        // ticks with no new frame (the last commands kept)
  std::uint64_t silences = 0;       // times the board fell silent for `hold` (module stopped)
  std::uint64_t dock_commands = 0;  // docking frames applied to the world
  std::uint64_t dock_refused = 0;   // ... that the world refused
  std::uint64_t unsent = 0;         // frames not written at all: the line was down
  std::uint64_t line_losses = 0;    // times the device went away
  std::uint64_t line_reopens = 0;   // times it was opened again
  kernel::Duration line_down{0};    // in all, the outage in progress included
  bool line_open = true;
  bool answered = false;  // the handshake was answered
  std::uint32_t last_applied = 0;

  std::uint64_t bad_frames() const { return decoder.dropped() + malformed; }
};

std::string describe(const HilOrganismStats& s);

class HilOrganism {
 public:
  // `session` was created on `executor` and not started; `module` is the board's (its index).
  // Fails when the module has events or hooks over the organism bus, or is out of range.
  static kernel::Result<std::unique_ptr<HilOrganism>> create(OrganismSession& session,
                                                             kernel::VirtualTimeExecutor& executor, std::size_t module,
                                                             std::shared_ptr<io::IOStream> port,
                                                             HilOrganismOptions options = {});
  // What create() checks of the scenario: the module exists, has no events and no hooks over
  // the organism bus. An error at its place in the file.
  static kernel::Status check(const Scenario& scenario, std::size_t module);
  ~HilOrganism();
  HilOrganism(const HilOrganism&) = delete;
  HilOrganism& operator=(const HilOrganism&) = delete;

  // The handshake: until the board answered, or `timeout` of wall time. Fails on timeout or when
  // the line fails.
  kernel::Status wait_for_board(kernel::Duration timeout);
  // Starts the session (at the first call) and runs `ticks` ticks. Returns the ticks done.
  kernel::Result<std::uint64_t> run_ticks(std::uint64_t ticks);

  HilOrganismStats stats() const;
  std::uint64_t ticks() const { return seq_; }
  const HilModuleLayout& layout() const { return layout_; }

 private:
  HilOrganism(OrganismSession& session, kernel::VirtualTimeExecutor& executor, std::size_t module,
              std::shared_ptr<io::IOStream> port, HilOrganismOptions options);
  void send_sensors(std::uint32_t seq);
  // Reads what came for up to `wait` (0: what is there); true once an answer to `want` came.
  bool read_board(kernel::Duration wait, std::uint32_t want);
  void apply();
  // Notices a line that went away and reopens it with backoff (before each tick and handshake).
  void watch_line();
  void event(const std::string& text);

  OrganismSession& session_;
  kernel::VirtualTimeExecutor& executor_;
  const std::size_t module_;
  std::shared_ptr<io::IOStream> port_;
  HilOrganismOptions options_;
  HilModuleLayout layout_;
  FrameCorruptor corruptor_;
  io::FrameDecoder decoder_{1024};
  std::vector<std::byte> buf_;
  std::vector<std::byte> frame_;
  std::vector<float> readings_;                   // the module's sensor values after the newest tick
  std::shared_ptr<std::vector<float>> observed_;  // ... as the runner's observer took them
  std::optional<HilModuleCommand> best_;
  std::vector<HilDockCommand> docks_;
  io::ReopenBackoff backoff_;
  std::uint32_t seq_ = 0;
  std::uint64_t quiet_ticks_ = 0;  // ticks since the last applied command
  bool started_ = false;
  bool silent_ = false;
  std::chrono::steady_clock::time_point wall_start_;
  mutable std::mutex stats_mu_;
  HilOrganismStats stats_;
};

}  // namespace symb::sim::mujoco
