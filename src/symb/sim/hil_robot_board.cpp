#include "symb/sim/hil_robot_board.hpp"

#include "symb/sim/hil_protocol.hpp"

namespace symb::sim {

HilRobotBoard::HilRobotBoard(kernel::VirtualTimeExecutor& executor, std::shared_ptr<io::IOStream> port,
                             FrameClockBoardOptions options)
    : FrameClockBoard(executor, std::move(port), std::move(options), "IR frame"),
      // Only this board's thread touches the devices: serve() runs the node, and a shell's
      // commands reach them as work injected into the same executor.
      ir_(std::make_shared<SimIrSensor>("ir", robot::DeviceThreads::kOneAtATime)),
      wheels_(std::make_shared<SimWheels>("wheels", robot::DeviceThreads::kOneAtATime)) {}

HilRobotBoard::~HilRobotBoard() { stop_clock(); }

RobotDevices HilRobotBoard::devices() const {
  RobotDevices d;
  d.ir = ir_;
  d.wheels = wheels_;
  return d;
}

std::vector<std::shared_ptr<io::Device>> HilRobotBoard::device_list() const { return {ir_, wheels_}; }

kernel::Result<FrameClockBoard::SensorFrame> HilRobotBoard::decode(std::span<const std::byte> payload) const {
  auto f = decode_ir_payload(payload);
  if (!f) return kernel::Error{f.error()};
  return SensorFrame{f->seq, std::vector<float>(f->ir.begin(), f->ir.end())};
}

void HilRobotBoard::publish(const std::vector<float>& values, kernel::Time now) {
  ir_->publish(std::span<const float>(values.data(), values.size()), now);
}

bool HilRobotBoard::answer(std::uint32_t seq) {
  const std::vector<float> out = wheels_->output();
  HilWheelFrame w;
  w.seq = seq;
  if (out.size() == 2) {
    w.left = out[0];
    w.right = out[1];
  }
  return send(encode_wheel_payload(w));
}

}  // namespace symb::sim
