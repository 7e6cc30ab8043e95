// HilModuleBoard: the board side of a 3D hardware-in-the-loop pair (docs/hil.md, "3D: one module
// on a board"; frames in hil_module_protocol.hpp). It gives one module's node the devices a
// MujocoRunner would give it, ir, hinge_state, hinge, wheels (a kind with them) and
// connector_<name>, but fed from and answering to a serial line, so the module's RobotSystem is
// built exactly as in process (RobotDevices::module = device_lookups()) and runs the same task
// graph.
//
// Time: the board's node runs on a VirtualTimeExecutor whose clock the simulator's frames drive.
// A clock activity stands where the MujocoRunner stands in process (the same priority, at the
// control period): its tick k publishes sensor frame k, stamped with the tick's node time. When
// sensor frame k arrives, serve() runs the executor up to just before tick k + 1, which is
// everything the node does before the world's next step in process, and answers [k, left, right,
// hinge] with the actuators' outputs then. So a board that gets every frame computes exactly what
// the module's node computes in process, bit for bit (same seed, same inputs, same instants). A
// lost frame's tick publishes nothing (the node goes on with its last inputs) and is counted
// missed; the node's time still advances with the next frame.
//
// Docking: connector_<name>'s ioctls latch, unlatch, open and close are forwarded: they answer
// "sent to the simulator" and a docking frame goes out (before the answer of the frame the node
// was running), which the simulator applies to the world before its next step, as an in-process
// ioctl acts between two steps. The world's verdict comes back in the connector's readings (state,
// peer) of the next frame. `state` answers from the newest reading.
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
#include "symb/io/stream.hpp"
#include "symb/kernel/result.hpp"
#include "symb/kernel/time.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/robot/actuator.hpp"
#include "symb/robot/robot_task_types.hpp"
#include "symb/robot/sensor.hpp"
#include "symb/sim/mujoco/hil_module_protocol.hpp"
#include "symb/sim/mujoco/module_kind.hpp"

namespace symb::sim::mujoco {

struct HilModuleBoardOptions {
  kernel::Duration control_period = std::chrono::milliseconds(30);
  // The link counts as lost after this many control periods of wall time without a sensor frame.
  int lost_periods = 10;
  // Receives the board's own events ("link lost", "link back after 120 ms", refused frames).
  std::function<void(const std::string&)> on_event;
};

struct HilModuleBoardStats {
  io::FrameStats decoder;           // dropped(): frames the CRC or the framing refused
  std::uint64_t frames = 0;         // sensor frames passed to the node
  std::uint64_t malformed = 0;      // good frames that are no sensor frame of this module
  std::uint64_t out_of_order = 0;   // sequence not newer than the last one: dropped
  std::uint64_t missed = 0;         // sequence numbers skipped (lost or corrupted frames)
  std::uint64_t handshakes = 0;     // seq 0 frames answered
  std::uint64_t restarts = 0;       // seq 0 after others: a new run, which this board does not serve
  std::uint64_t answers = 0;        // command frames the line took
  std::uint64_t dock_commands = 0;  // docking frames the line took
  std::uint64_t write_errors = 0;   // frames the line did not take
  std::uint64_t link_losses = 0;
  std::uint64_t link_recoveries = 0;
  std::uint32_t last_seq = 0;

  std::uint64_t bad_frames() const { return decoder.dropped() + malformed; }
};

// "frames 333 good, 1 bad (crc 1), 1 missed; answers 334, docking 1; ..."
std::string describe(const HilModuleBoardStats& s);

class HilModuleBoard {
 public:
  // `kind`: the module's, from the scenario (both sides read the same file). Throws
  // std::invalid_argument unless the period is in (0, 1 s].
  HilModuleBoard(kernel::VirtualTimeExecutor& executor, const ModuleKind& kind, std::shared_ptr<io::IOStream> port,
                 HilModuleBoardOptions options = {});
  ~HilModuleBoard();
  HilModuleBoard(const HilModuleBoard&) = delete;
  HilModuleBoard& operator=(const HilModuleBoard&) = delete;

  // The devices by name, for RobotDevices::module; and all of them, for a shell's device table.
  robot::RobotDevices device_lookups() const;
  std::vector<std::shared_ptr<io::Device>> devices() const;
  const HilModuleLayout& layout() const { return layout_; }

  // Starts the clock (its first tick one period from now, as the runner's). Call once the node
  // is built; fails when the port cannot be opened.
  kernel::Status start();
  // Reads the line for up to `timeout` of wall time and handles every frame that came (each
  // sensor frame runs the node to its next step and answers). Returns the sensor frames handled;
  // fails when the line is gone (end of stream, an I/O error).
  kernel::Result<std::size_t> serve(kernel::Duration timeout);

  HilModuleBoardStats stats() const;

  struct Shared;  // the state the devices and the clock share (public so the .cpp can name it)

 private:
  class Clock;
  void handle(std::span<const std::byte> payload, std::size_t& handled);
  void send(const std::vector<std::byte>& payload, bool dock);
  void event(const std::string& text);

  kernel::VirtualTimeExecutor& executor_;
  HilModuleLayout layout_;
  std::shared_ptr<io::IOStream> port_;
  HilModuleBoardOptions options_;
  std::shared_ptr<Shared> shared_;
  std::unique_ptr<Clock> clock_;
  io::FrameDecoder decoder_{1024};
  std::vector<std::byte> buf_;
  std::vector<std::byte> frame_;
  std::chrono::steady_clock::time_point last_frame_wall_;
  bool link_up_ = false;
  std::uint64_t recoveries_seen_ = 0;  // link_recoveries as this thread last wrote it
  bool started_ = false;
  mutable std::mutex stats_mu_;
  HilModuleBoardStats stats_;
};

}  // namespace symb::sim::mujoco
