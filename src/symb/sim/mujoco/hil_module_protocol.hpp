// Hardware in the loop in 3D: what a simulator running an organism and the board running one of
// its modules say to each other over a serial line (docs/hil.md, "3D: one module on a board").
// It generalises the 2D frames (hil_protocol.hpp): the simulator sends the module's sensor devices
// in a fixed order, the board answers with its actuator commands, and docking commands the
// board's controller or shell gives its connectors travel as frames of their own. Every frame is
// an io frame (0x00 | COBS(version | payload | CRC-16) | 0x00); the layout follows from the
// module's kind, which both sides read from the same scenario:
//
//   simulator -> board  'N' [seq, ir front, back, left, right, hinge angle, hinge speed,
//                            (state, open, peer, beacon distance, bearing, heading) per connector in the kind's order]
//   board -> simulator  'N' [seq, wheels left, right, hinge target]   (a kind with wheels)
//                       'N' [seq, hinge target]                        (a kind without)
//                       'D' seq (u32 LE) connector (u8) op (u8)         a docking command
//
// Values are the devices' own (mujoco_devices.hpp): IR proximity 0..1, rad and rad/s, connector
// state 0 free / 1 aligned / 2 docked, open 0/1, the partner's module index or -1; wheel speeds in
// Thymio motor units, the hinge target in rad. seq is the world's tick count, with the 2D rules:
// 0 is the handshake, it travels as a float32 (exact up to kHilMaxSequence), an answer echoes the
// newest sensor frame the board used.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "symb/kernel/result.hpp"
#include "symb/sim/mujoco/module_kind.hpp"
#include "symb/sim/mujoco/mujoco_devices.hpp"

namespace symb::sim::mujoco {

// The frame sizes of one module kind.
struct HilModuleLayout {
  bool wheels = true;
  std::vector<std::string> connectors;  // the kind's connector names, in its order

  static HilModuleLayout of(const ModuleKind& kind);
  // seq + 4 IR + 2 hinge + a connector's whole reading (kConnectorChannels: state, open, peer and
  // the docking beacon's distance, bearing, heading) per connector.
  std::size_t sensor_values() const { return 1 + 4 + 2 + kConnectorChannels * connectors.size(); }
  // seq + (left, right) + hinge.
  std::size_t command_values() const { return 1 + (wheels ? 2 : 0) + 1; }
};

inline constexpr std::size_t kHilSensorIr = 1;         // index of ir front in a sensor frame
inline constexpr std::size_t kHilSensorHinge = 5;      // hinge angle; hinge speed follows
inline constexpr std::size_t kHilSensorConnector = 7;  // the first connector's state

struct HilModuleSensors {
  std::uint32_t seq = 0;
  std::vector<float> values;  // sensor_values() - 1, in the order above
};

struct HilModuleCommand {
  std::uint32_t seq = 0;
  float left = 0, right = 0;  // 0 for a kind without wheels
  float hinge = 0;
};

enum class HilDockOp : std::uint8_t { kLatch = 1, kUnlatch = 2, kOpen = 3, kClose = 4 };
std::string_view dock_op_name(HilDockOp op);

struct HilDockCommand {
  std::uint32_t seq = 0;
  std::uint8_t connector = 0;  // index in the layout's connectors
  HilDockOp op = HilDockOp::kLatch;
};

// Encoders take values of the right count (they are the caller's own); decoders refuse a payload
// of another kind or count, a sequence number that is not an integer in [0, kHilMaxSequence] and
// NaN values, saying which.
std::vector<std::byte> encode_module_sensors(const HilModuleSensors& f);
kernel::Result<HilModuleSensors> decode_module_sensors(const HilModuleLayout& layout,
                                                       std::span<const std::byte> payload);
std::vector<std::byte> encode_module_command(const HilModuleLayout& layout, const HilModuleCommand& f);
std::vector<std::byte> encode_dock_command(const HilDockCommand& c);

// What the board sends: an actuator answer or a docking command.
struct HilBoardFrame {
  bool dock = false;
  HilModuleCommand command;  // when !dock
  HilDockCommand dock_command;
};
kernel::Result<HilBoardFrame> decode_board_frame(const HilModuleLayout& layout, std::span<const std::byte> payload);

}  // namespace symb::sim::mujoco
