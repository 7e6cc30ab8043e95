#include "symb/sim/hil_protocol.hpp"

#include <algorithm>
#include <cmath>

#include "symb/io/stream_task.hpp"

namespace symb::sim {

namespace {

std::string count_error(const char* what, std::size_t want, std::size_t got) {
  return std::string(what) + " frame: expected " + std::to_string(want) + " numbers, got " + std::to_string(got);
}

}  // namespace

std::optional<std::uint32_t> sequence_of(float v) {
  if (!std::isfinite(v) || v < 0 || v > static_cast<float>(kHilMaxSequence) || std::floor(v) != v) return std::nullopt;
  return static_cast<std::uint32_t>(v);
}

std::vector<std::byte> encode_ir_payload(const HilIrFrame& f) {
  float v[kHilIrValues];
  v[0] = static_cast<float>(f.seq);
  for (std::size_t i = 0; i < kIrCount; ++i) v[1 + i] = f.ir[i];
  return io::encode_numbers(v);
}

std::vector<std::byte> encode_wheel_payload(const HilWheelFrame& f) {
  const float v[kHilWheelValues] = {static_cast<float>(f.seq), f.left, f.right};
  return io::encode_numbers(v);
}

kernel::Result<HilIrFrame> decode_ir_payload(std::span<const std::byte> payload) {
  auto numbers = io::decode_numbers(payload);
  if (!numbers) return kernel::Error{"IR frame: not a number frame (" + std::to_string(payload.size()) + " bytes)"};
  if (numbers->size() != kHilIrValues) return kernel::Error{count_error("IR", kHilIrValues, numbers->size())};
  const auto seq = sequence_of((*numbers)[0]);
  if (!seq) return kernel::Error{"IR frame: bad sequence number " + std::to_string((*numbers)[0])};
  HilIrFrame f;
  f.seq = *seq;
  for (std::size_t i = 0; i < kIrCount; ++i) {
    const float v = (*numbers)[1 + i];
    if (std::isnan(v))
      return kernel::Error{"IR frame " + std::to_string(f.seq) + ": ir" + std::to_string(i) + " is NaN"};
    f.ir[i] = v;
  }
  return f;
}

kernel::Result<HilWheelFrame> decode_wheel_payload(std::span<const std::byte> payload) {
  auto numbers = io::decode_numbers(payload);
  if (!numbers) return kernel::Error{"wheel frame: not a number frame (" + std::to_string(payload.size()) + " bytes)"};
  if (numbers->size() != kHilWheelValues) return kernel::Error{count_error("wheel", kHilWheelValues, numbers->size())};
  const auto seq = sequence_of((*numbers)[0]);
  if (!seq) return kernel::Error{"wheel frame: bad sequence number " + std::to_string((*numbers)[0])};
  HilWheelFrame f;
  f.seq = *seq;
  const float l = (*numbers)[1], r = (*numbers)[2];
  if (!std::isfinite(l) || !std::isfinite(r))
    return kernel::Error{"wheel frame " + std::to_string(f.seq) + ": speed not finite"};
  f.left = std::clamp(l, -kHilWheelLimit, kHilWheelLimit);
  f.right = std::clamp(r, -kHilWheelLimit, kHilWheelLimit);
  return f;
}

bool corrupt_frame(std::span<std::byte> frame, kernel::RandomStream& random) {
  // The body lies between the delimiters; tolerate a frame given without them.
  std::size_t begin = 0, end = frame.size();
  while (begin < end && frame[begin] == std::byte{0}) ++begin;
  while (end > begin && frame[end - 1] == std::byte{0}) --end;
  // COBS: a code byte c is followed by c - 1 data bytes, then the next code byte.
  std::vector<std::size_t> data;
  for (std::size_t pos = begin; pos < end;) {
    const auto code = static_cast<std::size_t>(frame[pos]);
    for (std::size_t k = pos + 1; k < pos + code && k < end; ++k) data.push_back(k);
    pos += code == 0 ? 1 : code;
  }
  if (data.empty()) return false;
  const std::size_t at = data[random.below(data.size())];
  const auto old = static_cast<std::uint8_t>(frame[at]);
  // Another value in 1..255: 254 choices, skipping the old one.
  auto v = static_cast<std::uint8_t>(1 + random.below(254));
  if (v >= old) ++v;
  frame[at] = static_cast<std::byte>(v);
  return true;
}

void FrameCorruptor::feed(std::span<const std::byte> in, std::vector<std::byte>& out) {
  for (std::byte b : in) {
    if (b != std::byte{0}) {
      partial_.push_back(b);
      // A stream with no delimiters is not frames: pass it on rather than hold it forever.
      if (partial_.size() > 4096) {
        out.insert(out.end(), partial_.begin(), partial_.end());
        partial_.clear();
      }
      continue;
    }
    if (!partial_.empty()) {
      const bool hit = roll() && corrupt_frame(partial_, random_);
      count(hit);
      out.insert(out.end(), partial_.begin(), partial_.end());
      partial_.clear();
    }
    out.push_back(b);
  }
}

}  // namespace symb::sim
