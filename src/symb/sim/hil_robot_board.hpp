// HilRobotBoard: the board side of a 2D hardware-in-the-loop pair whose clock the simulator's
// frames drive (`symb board --lockstep`, docs/hil.md). It gives one robot's node the devices the
// world runner gives it in process, `ir` (a SimIrSensor) and `wheels` (a SimWheels), but fed from
// and answering to a serial line in the 2D protocol (hil_protocol.hpp), so the robot's
// RobotSystem is built exactly as in process (RobotDevices{ir, wheels}) and runs the same task
// graph: the default device tasks, the actuator sink's watchdog included.
//
// Its clock is FrameClockBoard's: the clock's tick k publishes IR frame k to `ir`, and frame k
// runs the node up to just before tick k + 1, then [k, left, right] answers with what `wheels`
// was last told. So the controller's own ticks and the wheels' watchdog fall where they fall in
// process, however late a frame comes or however long the board is kept off its core, and with
// `symb sim --lockstep` the run is the in-process one bit for bit.
//
// The board on the wall clock (board_link.hpp, the paper's task graph on OS threads) is the other
// way to run a 2D board: it shows how a control system copes with real time, this one checks that
// it computes what it computes in process.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "symb/io/stream.hpp"
#include "symb/kernel/virtual_time_executor.hpp"
#include "symb/sim/frame_clock_board.hpp"
#include "symb/sim/robot_system.hpp"
#include "symb/sim/sim_drivers.hpp"

namespace symb::sim {

using HilRobotBoardStats = FrameClockStats;

class HilRobotBoard final : public FrameClockBoard {
 public:
  // Throws std::invalid_argument as FrameClockBoard does.
  HilRobotBoard(kernel::VirtualTimeExecutor& executor, std::shared_ptr<io::IOStream> port,
                FrameClockBoardOptions options = {});
  ~HilRobotBoard() override;

  // The devices, for RobotSystem::build; and both, for a shell's device table.
  RobotDevices devices() const;
  std::vector<std::shared_ptr<io::Device>> device_list() const;

  HilRobotBoardStats stats() const { return link_stats(); }

 private:
  kernel::Result<SensorFrame> decode(std::span<const std::byte> payload) const override;
  void publish(const std::vector<float>& values, kernel::Time now) override;
  bool answer(std::uint32_t seq) override;

  std::shared_ptr<SimIrSensor> ir_;
  std::shared_ptr<SimWheels> wheels_;
};

}  // namespace symb::sim
