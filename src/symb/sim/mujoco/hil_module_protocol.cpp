#include "symb/sim/mujoco/hil_module_protocol.hpp"

#include <cmath>
#include <cstring>

#include "symb/io/stream_task.hpp"
#include "symb/sim/hil_protocol.hpp"

namespace symb::sim::mujoco {

namespace {

constexpr std::byte kDockTag{'D'};
constexpr std::size_t kDockSize = 1 + 4 + 1 + 1;

std::string count_error(const char* what, std::size_t want, std::size_t got) {
  return std::string(what) + " frame: expected " + std::to_string(want) + " numbers, got " + std::to_string(got);
}

}  // namespace

HilModuleLayout HilModuleLayout::of(const ModuleKind& kind) {
  HilModuleLayout l;
  l.wheels = kind.has_wheels;
  for (const ConnectorSpec& c : kind.connectors) l.connectors.push_back(c.name);
  return l;
}

std::string_view dock_op_name(HilDockOp op) {
  switch (op) {
    case HilDockOp::kLatch: return "latch";
    case HilDockOp::kUnlatch: return "unlatch";
    case HilDockOp::kOpen: return "open";
    case HilDockOp::kClose: return "close";
  }
  return "?";
}

std::vector<std::byte> encode_module_sensors(const HilModuleSensors& f) {
  std::vector<float> v;
  v.reserve(1 + f.values.size());
  v.push_back(static_cast<float>(f.seq));
  v.insert(v.end(), f.values.begin(), f.values.end());
  return io::encode_numbers(v);
}

kernel::Result<HilModuleSensors> decode_module_sensors(const HilModuleLayout& layout,
                                                       std::span<const std::byte> payload) {
  auto numbers = io::decode_numbers(payload);
  if (!numbers) return kernel::Error{"sensor frame: not a number frame (" + std::to_string(payload.size()) + " bytes)"};
  if (numbers->size() != layout.sensor_values())
    return kernel::Error{count_error("sensor", layout.sensor_values(), numbers->size())};
  const auto seq = sequence_of((*numbers)[0]);
  if (!seq) return kernel::Error{"sensor frame: bad sequence number " + std::to_string((*numbers)[0])};
  HilModuleSensors f;
  f.seq = *seq;
  f.values.assign(numbers->begin() + 1, numbers->end());
  for (std::size_t i = 0; i < f.values.size(); ++i)
    if (std::isnan(f.values[i]))
      return kernel::Error{"sensor frame " + std::to_string(f.seq) + ": value " + std::to_string(i + 1) + " is NaN"};
  return f;
}

std::vector<std::byte> encode_module_command(const HilModuleLayout& layout, const HilModuleCommand& f) {
  std::vector<float> v{static_cast<float>(f.seq)};
  if (layout.wheels) {
    v.push_back(f.left);
    v.push_back(f.right);
  }
  v.push_back(f.hinge);
  return io::encode_numbers(v);
}

std::vector<std::byte> encode_dock_command(const HilDockCommand& c) {
  std::vector<std::byte> out(kDockSize);
  out[0] = kDockTag;
  for (std::size_t i = 0; i < 4; ++i) out[1 + i] = static_cast<std::byte>((c.seq >> (8 * i)) & 0xFF);
  out[5] = static_cast<std::byte>(c.connector);
  out[6] = static_cast<std::byte>(c.op);
  return out;
}

kernel::Result<HilBoardFrame> decode_board_frame(const HilModuleLayout& layout, std::span<const std::byte> payload) {
  HilBoardFrame f;
  if (!payload.empty() && payload[0] == kDockTag) {
    if (payload.size() != kDockSize)
      return kernel::Error{"docking frame: expected " + std::to_string(kDockSize) + " bytes, got " +
                           std::to_string(payload.size())};
    std::uint32_t seq = 0;
    for (std::size_t i = 0; i < 4; ++i) seq |= std::to_integer<std::uint32_t>(payload[1 + i]) << (8 * i);
    if (seq > kHilMaxSequence) return kernel::Error{"docking frame: bad sequence number " + std::to_string(seq)};
    const auto connector = std::to_integer<std::uint8_t>(payload[5]);
    const auto op = std::to_integer<std::uint8_t>(payload[6]);
    if (connector >= layout.connectors.size())
      return kernel::Error{"docking frame " + std::to_string(seq) + ": no connector " + std::to_string(connector) +
                           " (the kind has " + std::to_string(layout.connectors.size()) + ")"};
    if (op < 1 || op > 4)
      return kernel::Error{"docking frame " + std::to_string(seq) + ": unknown command " + std::to_string(op)};
    f.dock = true;
    f.dock_command = {seq, connector, static_cast<HilDockOp>(op)};
    return f;
  }
  auto numbers = io::decode_numbers(payload);
  if (!numbers)
    return kernel::Error{"command frame: not a number frame (" + std::to_string(payload.size()) + " bytes)"};
  if (numbers->size() != layout.command_values())
    return kernel::Error{count_error("command", layout.command_values(), numbers->size())};
  const auto seq = sequence_of((*numbers)[0]);
  if (!seq) return kernel::Error{"command frame: bad sequence number " + std::to_string((*numbers)[0])};
  for (float v : *numbers)
    if (!std::isfinite(v)) return kernel::Error{"command frame " + std::to_string(*seq) + ": a value is not finite"};
  f.command.seq = *seq;
  std::size_t i = 1;
  if (layout.wheels) {
    f.command.left = (*numbers)[i++];
    f.command.right = (*numbers)[i++];
  }
  f.command.hinge = (*numbers)[i];
  return f;
}

}  // namespace symb::sim::mujoco
