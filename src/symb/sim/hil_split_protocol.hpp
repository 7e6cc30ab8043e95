// The frames of a split world (hil_split_world.hpp, docs/bus.md "A world split over processes"):
// the 2D hardware-in-the-loop protocol (hil_protocol.hpp) with the two things a robot's node in
// another process needs beyond a board's IR, both io number frames:
//
//   world -> robot   hello    [0, seed0, seed1, seed2, seed3, robot index, robot count, digest0,
//                             digest1]  the run's seed and the robot's digest (robot_digest) in
//                             16-bit pieces (a float32 carries 24 bits exactly), repeated every
//                             period until the robot answers
//   world -> robot   sensors  [seq, ir0..ir6, x, y, heading, ground_left, ground_right]
//                             after world step seq (1, 2, ...): every reading the world runner
//                             publishes to a robot's devices, as the floats it publishes
//   world -> robot   bye      [-1, steps]  the run ended after `steps` steps (a clean end: the
//                             robot's process ends; without it, a world gone is a world lost)
//   robot -> world   wheels   [seq, left, right]  (HilWheelFrame): the answer to each sensor
//                             frame, and to the hello (seq 0) with what the node set before the
//                             world's first step, which step 1 applies (unlike a board's hello
//                             answer, which is never applied)
//
// In a world with a radio (world.radio, local_radio.hpp) one more frame, a byte frame, carries a
// radio message of a step, just before the frame it belongs to and in the same write:
//
//   either way       radio    'R' | seq (uint32 LE) | robot (uint32 LE) | the message's bytes
//                             world -> robot: a message the world's radio delivered to the robot
//                             at step seq, robot = its sender's index; zero or more before sensor
//                             frame seq, in the order the radio delivered them (senders by index).
//                             robot -> world: what the robot's radio task has to put on air at
//                             the world's next step (the newest message since its last answer),
//                             robot = its own index; at most one, before its answer to seq.
//
// The hello is what makes the robot's node the in-process one: it is built with the run's seed
// (robot_node_seed(seed, index)), and the index, the count and the digest check that both sides
// read the same scenario.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "symb/kernel/result.hpp"
#include "symb/sim/ground_model.hpp"
#include "symb/sim/hil_protocol.hpp"
#include "symb/sim/scenario.hpp"
#include "symb/sim/world.hpp"

namespace symb::sim {

inline constexpr std::size_t kHilHelloValues = 9;
inline constexpr std::byte kHilRadioTag{'R'};  // number frames begin with 'N' (io::encode_numbers)
inline constexpr std::size_t kHilRadioHeader = 9;
inline constexpr std::size_t kHilSplitSensorValues = 1 + kIrCount + 3 + kGroundCount;

struct HilSplitHello {
  std::uint64_t seed = 0;
  std::uint32_t robot = 0;  // its index in the scenario
  std::uint32_t robots = 0;
  std::uint32_t digest = 0;  // robot_digest of the world's scenario
};

// FNV-1a over what makes robot `index`'s node and its inputs: the control period, the arena, the
// robot count, the radio (range, longest message), and the robot's name, kind, tasks (name, type, parameters as
// written, priority, period, queue, autostart) and hooks. Two scenario files that differ there give different digests
// (program files a parameter names are not read).
std::uint32_t robot_digest(const Scenario& scenario, std::size_t index);

struct HilSplitSensors {
  std::uint32_t seq = 0;
  IrReadings ir{};
  float pose[3] = {0, 0, 0};  // x, y (cm), heading (rad): as SimPoseSensor publishes them
  GroundReadings ground{};
};

// A radio frame; `bytes` views the payload it was decoded from.
struct HilSplitRadio {
  std::uint32_t seq = 0;
  std::uint32_t robot = 0;
  std::span<const std::byte> bytes;
};

std::vector<std::byte> encode_hello_payload(const HilSplitHello& h);
std::vector<std::byte> encode_bye_payload(std::uint32_t steps);
// The steps of a bye frame; nothing when the payload is not one.
std::optional<std::uint32_t> decode_bye_payload(std::span<const std::byte> payload);
std::vector<std::byte> encode_split_sensors_payload(const HilSplitSensors& f);
// Refused: not a number frame, another count, a bad sequence number (a hello's is 0, a sensor
// frame's at least 1), seed pieces that are not integers in [0, 65535], NaN readings.
kernel::Result<HilSplitHello> decode_hello_payload(std::span<const std::byte> payload);
kernel::Result<HilSplitSensors> decode_split_sensors_payload(std::span<const std::byte> payload);
void encode_radio_payload(std::uint32_t seq, std::uint32_t robot, std::span<const std::byte> bytes,
                          std::vector<std::byte>& out);
// Whether `payload` claims to be a radio frame (its first byte): then decode_radio_payload() says
// whether it is a good one.
inline bool is_radio_payload(std::span<const std::byte> payload) {
  return !payload.empty() && payload[0] == kHilRadioTag;
}
// Refused: not a radio frame, shorter than its header, no bytes (a radio sends none such), a
// sequence number beyond kHilMaxSequence.
kernel::Result<HilSplitRadio> decode_radio_payload(std::span<const std::byte> payload);

}  // namespace symb::sim
