// HilModuleBoard: the board side of a 3D hardware-in-the-loop pair (docs/hil.md, "3D: one module
// on a board"; frames in hil_module_protocol.hpp). It gives one module's node the devices a
// MujocoRunner would give it, ir, hinge_state, hinge, wheels (a kind with them) and
// connector_<name>, but fed from and answering to a serial line, so the module's RobotSystem is
// built exactly as in process (RobotDevices::module = device_lookups()) and runs the same task
// graph.
//
// Time: FrameClockBoard's (frame_clock_board.hpp). The clock stands where the MujocoRunner stands
// in process; its tick k publishes sensor frame k to ir, hinge_state and the connectors, and frame
// k runs the node up to just before tick k + 1, then [k, left, right, hinge] answers with the
// actuators' outputs. So a board that gets every frame computes exactly what the module's node
// computes in process, bit for bit; a new run goes on from the node's time.
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

#include <atomic>
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
#include "symb/sim/frame_clock_board.hpp"
#include "symb/sim/mujoco/hil_module_protocol.hpp"
#include "symb/sim/mujoco/module_kind.hpp"

namespace symb::sim::mujoco {

using HilModuleBoardOptions = FrameClockBoardOptions;

struct HilModuleBoardStats : FrameClockStats {
  std::uint64_t dock_commands = 0;  // docking frames the line took (not taken: in write_errors)
};

// "frames 333 good, 1 bad (crc 1, malformed 0), 1 missed, ...; answers 334, docking 1, ..."
std::string describe(const HilModuleBoardStats& s);

class HilModuleBoard final : public FrameClockBoard {
 public:
  // `kind`: the module's, from the scenario (both sides read the same file). Throws
  // std::invalid_argument as FrameClockBoard does, and for more than 255 connectors.
  HilModuleBoard(kernel::VirtualTimeExecutor& executor, const ModuleKind& kind, std::shared_ptr<io::IOStream> port,
                 HilModuleBoardOptions options = {});
  ~HilModuleBoard() override;

  // The devices by name, for RobotDevices::module; and all of them, for a shell's device table.
  robot::RobotDevices device_lookups() const;
  std::vector<std::shared_ptr<io::Device>> devices() const;
  const HilModuleLayout& layout() const { return layout_; }

  HilModuleBoardStats stats() const;

  struct Shared;  // the state the devices and the board share (public so the .cpp can name it)

 private:
  kernel::Result<SensorFrame> decode(std::span<const std::byte> payload) const override;
  void publish(const std::vector<float>& values, kernel::Time now) override;
  bool answer(std::uint32_t seq) override;

  HilModuleLayout layout_;
  std::shared_ptr<Shared> shared_;
  std::atomic<std::uint64_t> dock_commands_{0}, dock_write_errors_{0};
};

}  // namespace symb::sim::mujoco
