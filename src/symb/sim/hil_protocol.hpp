// Hardware-in-the-loop protocol: what a simulator and a board say to each other over a serial
// line (the paper's Player/Stage setup, section V-A; docs/hil.md). Both directions are io number
// frames (0x00 | COBS(version | 'N' float32... | CRC-16) | 0x00):
//
//   simulator -> board   [seq, ir0, ..., ir6]   after every world step
//   board -> simulator   [seq, left, right]     seq echoes the newest IR frame the board used;
//                                               wheel speeds in Thymio motor units, -500..500
//
// The sequence number is the world's step count: 0 for the handshake (the world before its
// first step, repeated until the board answers; it also tells a running board that a new run
// began), then 1, 2, ... It travels as a float32, exact up to 2^24, so one run is limited to
// kHilMaxSequence steps (about 139 hours at 30 ms). The CRC finds corrupted frames; the sequence
// numbers find lost, duplicated and reordered ones, and late answers.
//
// This header also has the fault injector the tests and `symb link --corrupt` use: it changes
// one byte of a frame in a way the CRC is certain to catch (see corrupt_frame).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "symb/kernel/random_stream.hpp"
#include "symb/kernel/result.hpp"
#include "symb/sim/world.hpp"

namespace symb::sim {

inline constexpr std::uint32_t kHilMaxSequence = (1u << 24) - 1;
inline constexpr std::size_t kHilIrValues = 1 + kIrCount;  // seq + 7 IR
inline constexpr std::size_t kHilWheelValues = 3;          // seq + left + right
inline constexpr float kHilWheelLimit = 500.0f;            // Thymio motor units

struct HilIrFrame {
  std::uint32_t seq = 0;
  IrReadings ir{};
};

struct HilWheelFrame {
  std::uint32_t seq = 0;
  float left = 0;
  float right = 0;
};

// Payloads (the part inside the frame codec): number frames.
std::vector<std::byte> encode_ir_payload(const HilIrFrame& f);
std::vector<std::byte> encode_wheel_payload(const HilWheelFrame& f);
// Why a payload was refused: not a number frame, the wrong count, a sequence number that is not
// an integer in [0, kHilMaxSequence], a NaN. IR values are passed on as they are (the receiver
// conditions them); wheel speeds must be finite and are clamped to +-kHilWheelLimit.
kernel::Result<HilIrFrame> decode_ir_payload(std::span<const std::byte> payload);
kernel::Result<HilWheelFrame> decode_wheel_payload(std::span<const std::byte> payload);
// A float that carries a sequence number, as an integer; nothing when it is not one.
std::optional<std::uint32_t> sequence_of(float v);

// Fault injection. Changes one byte of the encoded frame `frame` (its COBS body, delimiters
// excluded) to another non-zero value, choosing among the data bytes only, never a COBS code
// byte: the decoded frame then differs from the sent one in exactly one byte, which CRC-16 always
// detects, and no zero appears, so the receiver's decoder sees exactly one bad frame (a CRC
// error, or a bad version if the version byte was hit) and loses nothing around it. Returns false
// (frame unchanged) when the body has no data byte.
bool corrupt_frame(std::span<std::byte> frame, kernel::RandomStream& random);

// Applies corrupt_frame to a fraction of the frames in a byte stream that arrives in arbitrary
// chunks (a relay): complete frames are passed on, corrupted with probability `p`; a partial
// frame waits for its end. Bytes are never added or removed.
class FrameCorruptor {
 public:
  FrameCorruptor(double p, std::uint64_t seed, std::uint64_t stream = 0) : p_(p), random_(seed, stream) {}
  // Appends to `out` what can be passed on now.
  void feed(std::span<const std::byte> in, std::vector<std::byte>& out);
  // Whether the next complete frame is corrupted (for senders that handle whole frames).
  bool roll() { return p_ > 0 && random_.uniform() < p_; }
  kernel::RandomStream& random() { return random_; }
  std::uint64_t frames() const { return frames_; }
  std::uint64_t corrupted() const { return corrupted_; }
  // Counts a frame the caller corrupted itself.
  void count(bool corrupted) {
    ++frames_;
    corrupted_ += corrupted ? 1 : 0;
  }

 private:
  double p_;
  kernel::RandomStream random_;
  std::vector<std::byte> partial_;
  std::uint64_t frames_ = 0;
  std::uint64_t corrupted_ = 0;
};

}  // namespace symb::sim
